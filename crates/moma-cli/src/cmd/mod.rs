//! One module per subcommand: each defines its clap `Args` and a `run` function.

pub mod bench;
pub mod dynamics;
pub mod eval;
pub mod ik;
pub mod inspect;
pub mod manipulability;
pub mod map_info;
pub mod plan;
pub mod reach_map;
pub mod scen;
pub mod simulate;
pub mod stability;
pub mod stability_map;
