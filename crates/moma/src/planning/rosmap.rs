//! ROS `map_server` maps: a YAML file naming an image (PGM, PNG) plus the thresholds
//! that turn grey values into occupied / free / unknown cells.
//!
//! Conventions followed (ROS 1 `map_server` and nav2 `map_io`):
//! * grey value `x` = integer mean of the colour channels (in `trinary` mode an alpha
//!   channel is averaged in too, as both implementations do "to preserve existing
//!   behaviour"); 16-bit images are scaled to 8 bits;
//! * occupancy `p = (255 − x) / 255`, or `x / 255` when `negate` is set;
//! * `trinary`: `p > occupied_thresh` → 100, `p < free_thresh` → 0, else −1 (strict
//!   comparisons as ROS 1; nav2 ≥ 2025-04 uses inclusive ones, which give the same counts
//!   on the usual saved values 0 / 205 / 254);
//! * `scale` (nav2): in between the thresholds → `round(100 (p − free)/(occ − free))`,
//!   a pixel with alpha < 255 → −1;
//! * `raw` (nav2): the grey value itself, values above 100 → −1 (negate ignored);
//! * image row 0 is the top; grid row 0 is the bottom (the image is flipped).

use super::grid::{FREE, MapKind, OCCUPIED, OccupancyGrid, UNKNOWN, check_size};
use crate::{Error, Result};
use std::path::{Path, PathBuf};

/// How grey values become cell values (`mode` key).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MapMode {
    /// Occupied / free / unknown only (the default).
    #[default]
    Trinary,
    /// Intermediate occupancies scaled into 1..=99.
    Scale,
    /// Grey value copied as the cell value.
    Raw,
}

/// The parameters of a ROS map (the YAML's keys, defaults filled in).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct RosMapMeta {
    /// Image file, resolved relative to the YAML's folder.
    pub image: PathBuf,
    /// Cell edge length (m/cell), > 0.
    pub resolution: f64,
    /// Pose `[x, y, yaw]` of the lower-left pixel's corner in the map frame.
    pub origin: [f64; 3],
    /// Whether white means occupied.
    pub negate: bool,
    /// Occupancy above which a cell is occupied (default 0.65).
    pub occupied_thresh: f64,
    /// Occupancy below which a cell is free (default 0.196).
    pub free_thresh: f64,
    /// Conversion mode (default trinary).
    pub mode: MapMode,
}

impl RosMapMeta {
    /// The legacy `map_server <image> <resolution>` defaults: origin (0, 0, 0), negate 0,
    /// occupied_thresh 0.65, free_thresh 0.196, trinary.
    pub fn legacy(image: impl Into<PathBuf>, resolution: f64) -> Self {
        Self {
            image: image.into(),
            resolution,
            origin: [0.0; 3],
            negate: false,
            occupied_thresh: DEFAULT_OCCUPIED_THRESH,
            free_thresh: DEFAULT_FREE_THRESH,
            mode: MapMode::Trinary,
        }
    }

    fn validate(&self, file: &Path) -> Result<()> {
        let bad = |m: String| Err(Error::parse(file, m));
        if !(self.resolution.is_finite() && self.resolution > 0.0) {
            return bad(format!(
                "field 'resolution': must be a positive number, got {}",
                self.resolution
            ));
        }
        if self.origin.iter().any(|v| !v.is_finite()) {
            return bad(format!(
                "field 'origin': values must be finite, got {:?}",
                self.origin
            ));
        }
        for (name, v) in [
            ("occupied_thresh", self.occupied_thresh),
            ("free_thresh", self.free_thresh),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return bad(format!("field '{name}': must lie in [0, 1], got {v}"));
            }
        }
        if self.free_thresh >= self.occupied_thresh {
            return bad(format!(
                "fields 'free_thresh' ({}) and 'occupied_thresh' ({}): free_thresh must be smaller",
                self.free_thresh, self.occupied_thresh
            ));
        }
        Ok(())
    }
}

/// Default `occupied_thresh` of the legacy loader.
pub const DEFAULT_OCCUPIED_THRESH: f64 = 0.65;
/// Default `free_thresh` of the legacy loader.
pub const DEFAULT_FREE_THRESH: f64 = 0.196;
/// Default resolution (m/cell) for a bare image without `--resolution`.
pub const DEFAULT_RESOLUTION: f64 = 0.05;

#[derive(serde::Deserialize)]
#[serde(untagged)]
enum FlagValue {
    Int(i64),
    Bool(bool),
    Float(f64),
}

#[derive(serde::Deserialize)]
struct RawYaml {
    image: Option<String>,
    resolution: Option<f64>,
    origin: Option<Vec<f64>>,
    negate: Option<FlagValue>,
    occupied_thresh: Option<f64>,
    free_thresh: Option<f64>,
    mode: Option<String>,
}

/// Reads a ROS map YAML (does not load the image).
pub fn read_ros_yaml(path: &Path) -> Result<RosMapMeta> {
    let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_ros_yaml(&text, path)
}

/// Parses the text of a ROS map YAML; `path` names the file in errors and anchors the
/// relative image path.
pub fn parse_ros_yaml(text: &str, path: &Path) -> Result<RosMapMeta> {
    let raw: RawYaml = serde_saphyr::from_str(text)
        .map_err(|e| Error::parse(path, format!("malformed map YAML: {e}")))?;
    let missing = |k: &str| Error::parse(path, format!("missing required field '{k}'"));
    let image = raw.image.ok_or_else(|| missing("image"))?;
    if image.trim().is_empty() {
        return Err(Error::parse(path, "field 'image' is empty"));
    }
    let resolution = raw.resolution.ok_or_else(|| missing("resolution"))?;
    let origin = raw.origin.ok_or_else(|| missing("origin"))?;
    if origin.len() != 3 {
        return Err(Error::parse(
            path,
            format!(
                "field 'origin': expected [x, y, yaw] (3 numbers), got {} numbers",
                origin.len()
            ),
        ));
    }
    let negate = match raw.negate {
        None => false,
        Some(FlagValue::Bool(b)) => b,
        Some(FlagValue::Int(0)) => false,
        Some(FlagValue::Int(1)) => true,
        Some(FlagValue::Float(f)) if f == 0.0 || f == 1.0 => f == 1.0,
        Some(_) => return Err(Error::parse(path, "field 'negate': expected 0 or 1")),
    };
    let mode = match raw.mode.as_deref().map(str::trim) {
        None | Some("trinary") => MapMode::Trinary,
        Some("scale") => MapMode::Scale,
        Some("raw") => MapMode::Raw,
        Some(other) => {
            return Err(Error::parse(
                path,
                format!("field 'mode': unknown mode '{other}' (expected trinary, scale or raw)"),
            ));
        }
    };
    let folder = path.parent().unwrap_or(Path::new(""));
    let image_path = Path::new(&image);
    let image = if image_path.is_absolute() {
        image_path.to_path_buf()
    } else {
        folder.join(image_path)
    };
    let meta = RosMapMeta {
        image,
        resolution,
        origin: [origin[0], origin[1], origin[2]],
        negate,
        occupied_thresh: raw.occupied_thresh.unwrap_or(DEFAULT_OCCUPIED_THRESH),
        free_thresh: raw.free_thresh.unwrap_or(DEFAULT_FREE_THRESH),
        mode,
    };
    meta.validate(path)?;
    Ok(meta)
}

/// Loads a ROS map from its YAML file.
pub fn load_ros_map(yaml: &Path) -> Result<(OccupancyGrid, RosMapMeta)> {
    let meta = read_ros_yaml(yaml)?;
    // A missing or unreadable image is a fault of the YAML's `image` field: name both.
    let grid = load_image_with_meta(&meta).map_err(|e| match e {
        Error::Io { path, source } => Error::parse(
            yaml,
            format!("field 'image': cannot read '{}': {source}", path.display()),
        ),
        other => other,
    })?;
    Ok((grid, meta))
}

/// Loads a bare image (PGM/PNG) with the legacy `map_server` defaults and the given
/// resolution (see [`RosMapMeta::legacy`]).
pub fn load_image_map(image: &Path, resolution: f64) -> Result<(OccupancyGrid, RosMapMeta)> {
    let meta = RosMapMeta::legacy(image, resolution);
    meta.validate(image)?;
    let grid = load_image_with_meta(&meta)?;
    Ok((grid, meta))
}

/// Loads the image named by `meta` and converts it with `meta`'s thresholds and mode.
pub fn load_image_with_meta(meta: &RosMapMeta) -> Result<OccupancyGrid> {
    let path = &meta.image;
    let bytes = std::fs::read(path).map_err(|source| Error::Io {
        path: path.clone(),
        source,
    })?;
    decode_image_map(&bytes, meta)
}

/// Decodes the bytes of a PGM/PNG map image (the file `meta` names, which only names it
/// in errors) and converts it with `meta`'s thresholds and mode.
pub fn decode_image_map(bytes: &[u8], meta: &RosMapMeta) -> Result<OccupancyGrid> {
    let path = &meta.image;
    let img = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| Error::parse(path, format!("cannot read image: {e}")))?
        .decode()
        .map_err(|e| Error::parse(path, format!("cannot decode image: {e}")))?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    check_size(w, h).map_err(|e| Error::parse(path, e.to_string()))?;
    // (grey value, alpha) per pixel in image order.
    let trinary = meta.mode == MapMode::Trinary;
    let pixels: Vec<(u8, u8)> = match img {
        image::DynamicImage::ImageLuma8(b) => b.pixels().map(|p| (p.0[0], 255)).collect(),
        image::DynamicImage::ImageLumaA8(b) => b
            .pixels()
            .map(|p| {
                let [l, a] = p.0;
                let grey = if trinary {
                    ((l as u32 + a as u32) / 2) as u8
                } else {
                    l
                };
                (grey, a)
            })
            .collect(),
        image::DynamicImage::ImageRgb8(b) => b
            .pixels()
            .map(|p| {
                (
                    ((p.0[0] as u32 + p.0[1] as u32 + p.0[2] as u32) / 3) as u8,
                    255,
                )
            })
            .collect(),
        image::DynamicImage::ImageLuma16(b) => b
            .pixels()
            .map(|p| (((p.0[0] as u32 + 128) / 257) as u8, 255))
            .collect(),
        other => {
            let has_alpha = other.color().has_alpha();
            let rgba = other.to_rgba8();
            rgba.pixels()
                .map(|p| {
                    let [r, g, b, a] = p.0;
                    let grey = if trinary && has_alpha {
                        ((r as u32 + g as u32 + b as u32 + a as u32) / 4) as u8
                    } else {
                        ((r as u32 + g as u32 + b as u32) / 3) as u8
                    };
                    (grey, a)
                })
                .collect()
        }
    };
    let mut cells = vec![UNKNOWN; w * h];
    for row in 0..h {
        let grid_row = h - 1 - row;
        for col in 0..w {
            let (x, alpha) = pixels[row * w + col];
            cells[grid_row * w + col] = grey_to_cell(meta, x, alpha);
        }
    }
    Ok(OccupancyGrid {
        width: w,
        height: h,
        resolution: meta.resolution,
        origin: meta.origin,
        cells,
        kind: MapKind::Ros,
    })
}

/// Converts one grey value (with its alpha) to a cell value under `meta`.
pub fn grey_to_cell(meta: &RosMapMeta, x: u8, alpha: u8) -> i8 {
    if meta.mode == MapMode::Raw {
        return if x <= 100 { x as i8 } else { UNKNOWN };
    }
    let p = if meta.negate {
        x as f64 / 255.0
    } else {
        (255.0 - x as f64) / 255.0
    };
    if p > meta.occupied_thresh {
        OCCUPIED
    } else if p < meta.free_thresh {
        FREE
    } else if meta.mode == MapMode::Scale {
        if alpha < 255 {
            UNKNOWN
        } else {
            (100.0 * (p - meta.free_thresh) / (meta.occupied_thresh - meta.free_thresh))
                .round()
                .clamp(0.0, 100.0) as i8
        }
    } else {
        UNKNOWN
    }
}
