//! The ROS `map_server` YAML parser (thresholds, mode, origin) on arbitrary text.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(meta) =
        moma::planning::rosmap::parse_ros_yaml(text, std::path::Path::new("fuzz.yaml"))
    {
        // a parsed threshold pair must convert every grey level without panicking
        for x in [0u8, 1, 127, 128, 254, 255] {
            let _ = moma::planning::rosmap::grey_to_cell(&meta, x, 255);
        }
    }
});
