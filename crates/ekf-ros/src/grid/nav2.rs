//! The map files of ROS `map_server` / Nav2 (`nav2_map_server`): a YAML file naming an image
//! (PGM or PNG) and saying how its pixels become occupancies. Read with the same rules as
//! Nav2's `map_io` (so a map loads here as it loads there), written as `map_saver` writes a
//! trinary map.
//!
//! ```yaml
//! image: aces.pgm          # relative to the YAML file's directory, or absolute
//! mode: trinary            # trinary (default), scale or raw
//! resolution: 0.05         # m per pixel
//! origin: [-20.0, -15.5, 0.0]   # x, y, yaw of the lower-left pixel
//! negate: 0                # 1: black is free
//! occupied_thresh: 0.65
//! free_thresh: 0.25
//! ```
//!
//! A pixel's `shade` is the mean of its channels over 255 (in trinary mode an alpha channel
//! counts as one of them), its occupancy `occ = 1 − shade` (`shade` if `negate`). Trinary:
//! `occ > occupied_thresh` is occupied (100), `occ < free_thresh` free (0), else unknown.
//! Scale: a pixel that is not opaque is unknown, else occupied / free by the same
//! thresholds and between them `round(100·(occ − free)/(occupied − free))`. Raw: the
//! shade times 255 is the occupancy if it is in 0..=100, else unknown. The image's top row
//! is the grid's last.

use super::{OccupancyGrid, FREE, OCCUPIED, UNKNOWN};
use ekf_core::Pose2;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// `occupied_thresh` written by [`save`] (`map_saver`'s default).
pub const SAVED_OCCUPIED_THRESH: f64 = 0.65;
/// `free_thresh` written by [`save`]: ROS 1 `map_saver`'s 0.196, just below the occupancy
/// 0.196 of the unknown grey 205, so that unknown cells read back as unknown (Nav2's
/// default 0.25 reads them back as free).
pub const SAVED_FREE_THRESH: f64 = 0.196;

/// Grey levels `map_saver` writes in trinary mode.
const PIXEL_FREE: u8 = 254;
const PIXEL_OCCUPIED: u8 = 0;
const PIXEL_UNKNOWN: u8 = 205;

/// A map file that could not be read or written: the file and what was wrong.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {message}")]
pub struct GridFileError {
    /// The YAML or image file.
    pub path: PathBuf,
    /// What was wrong, naming the key where there is one.
    pub message: String,
}

impl GridFileError {
    fn new(path: &Path, message: impl Into<String>) -> Self {
        Self {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }
}

/// How pixels become occupancies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// Occupied, free or unknown by the thresholds.
    #[default]
    Trinary,
    /// As trinary, with occupancies between the thresholds kept and transparency unknown.
    Scale,
    /// The pixel value is the occupancy.
    Raw,
}

/// `negate` as Nav2 accepts it: an integer or a boolean.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(untagged)]
enum Negate {
    Int(i64),
    Bool(bool),
}

/// The YAML file's keys.
#[derive(Debug, Deserialize)]
struct MapYaml {
    image: String,
    resolution: f64,
    origin: Vec<f64>,
    negate: Negate,
    occupied_thresh: f64,
    free_thresh: f64,
    #[serde(default)]
    mode: Mode,
}

/// The YAML file [`save`] writes.
#[derive(Debug, Serialize)]
struct SavedYaml<'a> {
    image: &'a str,
    mode: Mode,
    resolution: f64,
    origin: [f64; 3],
    negate: u8,
    occupied_thresh: f64,
    free_thresh: f64,
}

/// Reads the map that `yaml` describes.
pub fn load(yaml: &Path) -> Result<OccupancyGrid, GridFileError> {
    let text =
        std::fs::read_to_string(yaml).map_err(|e| GridFileError::new(yaml, e.to_string()))?;
    let meta: MapYaml = serde_saphyr::from_str(&text)
        .map_err(|e| GridFileError::new(yaml, format!("not a map_server map description: {e}")))?;
    let bad = |key: &str, expected: &str, found: String| {
        GridFileError::new(
            yaml,
            format!("key '{key}': expected {expected}, found {found}"),
        )
    };
    if !(meta.resolution.is_finite() && meta.resolution > 0.0) {
        return Err(bad(
            "resolution",
            "a positive size in m",
            meta.resolution.to_string(),
        ));
    }
    let [x, y, yaw] = meta.origin[..] else {
        return Err(bad(
            "origin",
            "[x, y, yaw]",
            format!("{} values", meta.origin.len()),
        ));
    };
    if !(x.is_finite() && y.is_finite() && yaw.is_finite()) {
        return Err(bad(
            "origin",
            "finite [x, y, yaw]",
            format!("{:?}", meta.origin),
        ));
    }
    let (free, occupied) = (meta.free_thresh, meta.occupied_thresh);
    if !((0.0..=1.0).contains(&free) && (0.0..=1.0).contains(&occupied) && free < occupied) {
        return Err(bad(
            "free_thresh",
            "0 ≤ free_thresh < occupied_thresh ≤ 1",
            format!("free_thresh {free}, occupied_thresh {occupied}"),
        ));
    }
    let negate = match meta.negate {
        Negate::Int(i) => i != 0,
        Negate::Bool(b) => b,
    };
    if meta.image.is_empty() {
        return Err(bad("image", "the image file's name", "''".into()));
    }
    let image_path = yaml
        .parent()
        .map_or_else(|| PathBuf::from(&meta.image), |dir| dir.join(&meta.image));
    let image = image::open(&image_path)
        .map_err(|e| GridFileError::new(&image_path, format!("cannot read the map image: {e}")))?;
    let has_alpha = image.color().has_alpha();
    let rgba = image.to_rgba8();
    let (width, height) = (rgba.width() as usize, rgba.height() as usize);
    let mut grid = OccupancyGrid::filled(
        width,
        height,
        meta.resolution,
        Pose2::new(x, y, yaw),
        UNKNOWN,
    );
    for (px, py, pixel) in rgba.enumerate_pixels() {
        let [r, g, b, a] = pixel.0.map(f64::from);
        let shade = if meta.mode == Mode::Trinary && has_alpha {
            (r + g + b + a) / (4.0 * 255.0)
        } else {
            (r + g + b) / (3.0 * 255.0)
        };
        let occ = if negate { shade } else { 1.0 - shade };
        let cell = match meta.mode {
            Mode::Trinary if occ > occupied => OCCUPIED,
            Mode::Trinary if occ < free => FREE,
            Mode::Trinary => UNKNOWN,
            Mode::Scale if pixel.0[3] != u8::MAX => UNKNOWN,
            Mode::Scale if occ > occupied => OCCUPIED,
            Mode::Scale if occ < free => FREE,
            Mode::Scale => ((occ - free) / (occupied - free) * 100.0).round() as i8,
            Mode::Raw => {
                let v = (shade * 255.0).round();
                if (0.0..=100.0).contains(&v) {
                    v as i8
                } else {
                    UNKNOWN
                }
            }
        };
        grid.cells[(height - 1 - py as usize) * width + px as usize] = cell;
    }
    Ok(grid)
}

/// Writes `grid` as `map_saver` writes a trinary map: `yaml`, and beside it the PGM image
/// of the same stem (free 254, occupied 0, unknown 205; occupancies up to 20 % free, from
/// 65 % occupied). Each file is written to a temporary name and renamed into place, so a
/// reader never sees half a file. Returns the image's path.
pub fn save(grid: &OccupancyGrid, yaml: &Path) -> Result<PathBuf, GridFileError> {
    let image_path = yaml.with_extension("pgm");
    let image_name = image_path
        .file_name()
        .and_then(|n| n.to_str())
        .ok_or_else(|| GridFileError::new(yaml, "the file name must be valid UTF-8"))?;
    let (free_max, occupied_min) = (
        (SAVED_FREE_THRESH * 100.0).round() as i8,
        (SAVED_OCCUPIED_THRESH * 100.0).round() as i8,
    );
    let mut pixels = vec![PIXEL_UNKNOWN; grid.width * grid.height];
    for (i, &cell) in grid.cells.iter().enumerate() {
        let (ix, iy) = (i % grid.width, i / grid.width);
        pixels[(grid.height - 1 - iy) * grid.width + ix] = match cell {
            c if !(0..=100).contains(&c) => PIXEL_UNKNOWN,
            c if c <= free_max => PIXEL_FREE,
            c if c >= occupied_min => PIXEL_OCCUPIED,
            _ => PIXEL_UNKNOWN,
        };
    }
    let (w, h) = (
        u32::try_from(grid.width).map_err(|_| GridFileError::new(&image_path, "too wide"))?,
        u32::try_from(grid.height).map_err(|_| GridFileError::new(&image_path, "too high"))?,
    );
    let mut pgm = Vec::new();
    image::codecs::pnm::PnmEncoder::new(&mut pgm)
        .with_subtype(image::codecs::pnm::PnmSubtype::Graymap(
            image::codecs::pnm::SampleEncoding::Binary,
        ))
        .encode(pixels.as_slice(), w, h, image::ExtendedColorType::L8)
        .map_err(|e| GridFileError::new(&image_path, e.to_string()))?;
    let o = &grid.origin;
    let text = serde_saphyr::to_string(&SavedYaml {
        image: image_name,
        mode: Mode::Trinary,
        resolution: grid.resolution,
        origin: [o.x, o.y, o.theta],
        negate: 0,
        occupied_thresh: SAVED_OCCUPIED_THRESH,
        free_thresh: SAVED_FREE_THRESH,
    })
    .map_err(|e| GridFileError::new(yaml, e.to_string()))?;
    write_atomically(&image_path, &pgm)?;
    write_atomically(yaml, text.as_bytes())?;
    Ok(image_path)
}

/// Writes `bytes` to `path` through a temporary file renamed into place.
fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), GridFileError> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    std::fs::write(&tmp, bytes)
        .and_then(|()| std::fs::rename(&tmp, path))
        .map_err(|e| GridFileError::new(path, e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    /// A 3 × 2 PGM: top row 0, 128, 254; bottom row 205, 255, 60.
    const PGM: &[u8] = b"P5\n3 2\n255\n\x00\x80\xfe\xcd\xff\x3c";

    fn yaml(mode: &str, negate: &str) -> String {
        format!(
            "image: m.pgm\nmode: {mode}\nresolution: 0.1\norigin: [1.0, -2.0, 0.0]\n\
             negate: {negate}\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
        )
    }

    #[test]
    fn pixels_become_occupancies_as_in_nav2() {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), "m.pgm", PGM);
        let load_with = |mode: &str, negate: &str| {
            let y = write(dir.path(), "m.yaml", yaml(mode, negate).as_bytes());
            load(&y).unwrap()
        };
        let g = load_with("trinary", "0");
        assert_eq!((g.width, g.height, g.resolution), (3, 2, 0.1));
        assert_eq!(g.origin, Pose2::new(1.0, -2.0, 0.0));
        // Row 0 is the image's bottom row: 205 (occ 0.196: not < free_thresh) unknown,
        // 255 free, 60 (occ 0.76) occupied; then the top row: 0 occupied, 128 (0.498)
        // unknown, 254 free.
        assert_eq!(g.cells, [UNKNOWN, FREE, OCCUPIED, OCCUPIED, UNKNOWN, FREE]);
        let g = load_with("trinary", "true");
        assert_eq!(
            g.cells,
            [OCCUPIED, OCCUPIED, UNKNOWN, FREE, UNKNOWN, OCCUPIED]
        );
        // Scale keeps the middle: 128 → occ 0.498 → round(100·0.302/0.454) = 67.
        let g = load_with("scale", "0");
        assert_eq!(g.cells, [0, FREE, OCCUPIED, OCCUPIED, 67, FREE]);
        let g = load_with("raw", "0");
        assert_eq!(g.cells, [UNKNOWN, UNKNOWN, 60, 0, UNKNOWN, UNKNOWN]);
    }

    #[test]
    fn saved_maps_load_back_and_look_like_map_savers() {
        let dir = tempfile::tempdir().unwrap();
        let mut g = OccupancyGrid::filled(4, 3, 0.05, Pose2::new(-1.5, 2.25, 0.0), FREE);
        g.set(0, 0, OCCUPIED);
        g.set(3, 2, UNKNOWN);
        g.set(1, 1, 30); // between the thresholds: unknown
        let y = dir.path().join("out.yaml");
        let image = save(&g, &y).unwrap();
        assert_eq!(image, dir.path().join("out.pgm"));
        let pgm = std::fs::read(&image).unwrap();
        let pixels = &pgm[pgm.len() - 12..];
        assert_eq!(
            pixels,
            [254, 254, 254, 205, 254, 205, 254, 254, 0, 254, 254, 254],
            "top row first"
        );
        let back = load(&y).unwrap();
        g.set(1, 1, UNKNOWN);
        assert_eq!(back, g);
        let text = std::fs::read_to_string(&y).unwrap();
        for key in [
            "image: out.pgm",
            "mode: trinary",
            "negate: 0",
            "occupied_thresh: 0.65",
            "free_thresh: 0.196",
        ] {
            assert!(text.contains(key), "{key} in {text}");
        }
    }

    #[test]
    fn bad_files_name_the_file_and_key() {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), "m.pgm", PGM);
        let check = |text: &str, want: &str| {
            let y = write(dir.path(), "bad.yaml", text.as_bytes());
            let e = load(&y).unwrap_err().to_string();
            assert!(e.contains(want), "{e}");
            e
        };
        let e = check(
            &yaml("trinary", "0").replace("resolution: 0.1", "resolution: -1"),
            "key 'resolution'",
        );
        assert!(e.contains("bad.yaml"), "{e}");
        check(
            &yaml("trinary", "0").replace("[1.0, -2.0, 0.0]", "[1.0, -2.0]"),
            "key 'origin'",
        );
        check(
            &yaml("trinary", "0").replace("free_thresh: 0.196", "free_thresh: 0.9"),
            "free_thresh",
        );
        check(&yaml("sideways", "0"), "not a map_server map description");
        check(&yaml("trinary", "0").replace("negate: 0\n", ""), "negate");
        let e = check(
            &yaml("trinary", "0").replace("m.pgm", "gone.pgm"),
            "cannot read the map image",
        );
        assert!(e.contains("gone.pgm"), "{e}");
        write(dir.path(), "m.pgm", b"P5\n3 2\n255\n\x00");
        check(&yaml("trinary", "0"), "cannot read the map image");
    }
}
