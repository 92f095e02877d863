//! PGM/PNG map decoding (format guessed from the bytes) with the legacy trinary
//! thresholds, or the raw/scale modes picked by the first byte.
#![no_main]
use libfuzzer_sys::fuzz_target;
use moma::planning::{MapMode, RosMapMeta};

fuzz_target!(|data: &[u8]| {
    let Some((&sel, bytes)) = data.split_first() else {
        return;
    };
    let mut meta = RosMapMeta::legacy("fuzz.pgm", 0.05);
    meta.mode = [MapMode::Trinary, MapMode::Scale, MapMode::Raw][usize::from(sel % 3)];
    meta.negate = sel & 4 != 0;
    let _ = moma::planning::rosmap::decode_image_map(bytes, &meta);
});
