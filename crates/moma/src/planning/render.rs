//! Raster pictures of grids (PNG bytes) for reports and SVG overlays.

use crate::{Error, Result};

/// Encodes an RGB picture of a `width × height` grid as PNG: `colour(x, y)` gives the
/// colour of cell `(x, y)`; with `y_up` the grid's row 0 is drawn at the bottom (ROS
/// maps), otherwise at the top (Moving AI maps, images).
pub fn grid_png(width: usize, height: usize, y_up: bool, colour: impl Fn(usize, usize) -> [u8; 3]) -> Result<Vec<u8>> {
    let mut buf = Vec::with_capacity(width * height * 3);
    for r in 0..height {
        let y = if y_up { height - 1 - r } else { r };
        for x in 0..width {
            buf.extend_from_slice(&colour(x, y));
        }
    }
    let img = image::RgbImage::from_raw(width as u32, height as u32, buf)
        .ok_or_else(|| Error::invalid("picture", "buffer size mismatch"))?;
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png)
        .map_err(|e| Error::invalid("picture", format!("PNG encoding failed: {e}")))?;
    Ok(out.into_inner())
}
