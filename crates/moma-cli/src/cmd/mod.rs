//! One module per subcommand: each defines its clap `Args` and a `run` function;
//! `common` holds what several of them share (model and states loading, option parsing).

pub mod bench;
pub mod collision;
pub mod common;
pub mod derivatives;
pub mod dynamics;
pub mod eval;
pub mod ik;
pub mod inspect;
pub mod manipulability;
pub mod map_info;
pub mod mission;
pub mod osc;
pub mod plan;
pub mod reach_map;
pub mod render_report;
pub mod scen;
pub mod simulate;
pub mod simulate_common;
pub mod simulate_control;
pub mod simulate_space;
pub mod simulate_stability;
pub mod space;
pub mod stability;
pub mod stability_map;
pub mod sweep;
