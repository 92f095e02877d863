//! What the mission targets do with one parsed mission file: keep its paths on shipped
//! files ([`files`]), validate it and load its map and robot (`mission::scenario::from_file_with`, the
//! shipped files parsed once per process: [`files::Cached`]),
//! then the one cheap evaluation the loaded mission offers, the transport posture's
//! tip-over limits. A mission is never run (seconds per input).

use std::path::{Path, PathBuf};

use moma::mission::{self, MissionFile};

use crate::files;

pub fn check(mut file: MissionFile) {
    let map = file.map.file.to_string_lossy().into_owned();
    file.map.file = PathBuf::from(files::pick(&map, &files::MISSION_FILES));
    let urdf = file.robot.urdf.to_string_lossy().into_owned();
    file.robot.urdf = PathBuf::from(files::pick(&urdf, &files::MISSION_FILES));
    let base = files::scenarios();
    let Ok(m) = mission::scenario::from_file_with(file, Path::new("fuzz.toml"), &base, &files::Cached)
    else {
        return;
    };
    if let Ok(l) = mission::transport_tip_limits(&m) {
        let _ = format!("{l:?}");
    }
}
