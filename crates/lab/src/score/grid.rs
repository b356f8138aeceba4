//! The grid of a set of external lists (`grid.json`, docs/EXPERIMENTS.md "Scoring another
//! engine's lists"): which list a pixel reads, from its coordinates and its view depth.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::LabError;

/// The format name `grid.json` must carry.
pub const FORMAT: &str = "manylights-lists/1";

/// How a pixel's column and row map to the grid's x and y.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum ScreenMapping {
    /// `x = floor(px / tile_size[0])`, `y = floor(py / tile_size[1])` (pixel rows from the top):
    /// tiles of whole pixels, as Forward+ and this workbench's strategies use.
    Tiles {
        /// Tile width and height in pixels.
        tile_size: [u32; 2],
    },
    /// `x = floor((px + 0.5) X / W)`, `y = floor((py + 0.5) Y / H)`: the grid spread evenly
    /// over the image, as Bevy's shader looks clusters up.
    Proportional,
}

/// How a pixel's view depth `d` (the distance along the view axis, > 0) maps to a slice of
/// `Z`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Slicing {
    /// One slice (`Z = 1`): screen-space tiles.
    None,
    /// `floor((d - near) / (far - near) Z)`, clamped to `[0, Z - 1]`.
    Linear {
        /// Depth of the first slice's start.
        near: f64,
        /// Depth of the last slice's end.
        far: f64,
    },
    /// `floor(ln(d / near) / ln(far / near) Z)`, clamped to `[0, Z - 1]`.
    Exponential {
        /// Depth of the first slice's start.
        near: f64,
        /// Depth of the last slice's end.
        far: f64,
    },
    /// Bevy's: slice 0 is `[0, near)`, slice `k >= 1` is
    /// `[near (far / near)^((k - 1) / (Z - 1)), near (far / near)^(k / (Z - 1)))`, the last
    /// slice open-ended: `1 + floor(ln(d / near) (Z - 1) / ln(far / near))` for `d >= near`.
    NearSlice {
        /// The first slice's depth (Bevy's `first_slice_depth`).
        near: f64,
        /// The far bound of the slicing (Bevy's far plane of its clusters).
        far: f64,
    },
}

/// The order of the cells in the offsets array.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CellOrder {
    /// `(z Y + y) X + x`: x fastest, slices outermost.
    XFastest,
    /// `(y X + x) Z + z`: slices innermost (Bevy's).
    ZFastest,
}

/// `grid.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Grid {
    /// [`FORMAT`].
    pub format: String,
    /// Who wrote the lists, free text (an engine and its version).
    #[serde(default)]
    pub source: String,
    /// The image the lists are for, in pixels.
    pub width: u32,
    /// Its height.
    pub height: u32,
    /// Cells in x, y and z.
    pub dims: [u32; 3],
    /// Pixels to cells across the screen.
    pub screen: ScreenMapping,
    /// View depth to slices.
    pub slicing: Slicing,
    /// Order of the cells in the offsets.
    pub order: CellOrder,
    /// A file (`uint32`, one entry a light id the lists use) mapping the lists' light ids to
    /// the scene's light indices; none: the ids are the scene's indices.
    #[serde(default)]
    pub light_ids: Option<String>,
}

fn invalid(path: &Path, field: &str, value: impl std::fmt::Display, accepted: &str) -> LabError {
    LabError::Io {
        path: path.display().to_string(),
        message: format!("{field} = {value}: expected {accepted}"),
    }
}

impl Grid {
    /// Reads and checks `path` against the image (`width` x `height`) being scored.
    pub fn load(path: &Path, width: u32, height: u32) -> Result<Self, LabError> {
        let text = std::fs::read_to_string(path).map_err(|e| LabError::Io {
            path: path.display().to_string(),
            message: e.to_string(),
        })?;
        let grid: Grid = serde_json::from_str(&text).map_err(|e| LabError::Io {
            path: path.display().to_string(),
            message: format!("not a grid description: {e}"),
        })?;
        grid.check(path, width, height)?;
        Ok(grid)
    }

    /// The checks of [`Grid::load`]: the format, the image size, every pixel on the grid and
    /// the slicing's constants.
    pub fn check(&self, path: &Path, width: u32, height: u32) -> Result<(), LabError> {
        if self.format != FORMAT {
            return Err(invalid(path, "format", &self.format, FORMAT));
        }
        if (self.width, self.height) != (width, height) {
            return Err(invalid(
                path,
                "width x height",
                format!("{} x {}", self.width, self.height),
                &format!("the image scored, {width} x {height}"),
            ));
        }
        let [x, y, z] = self.dims;
        if x == 0 || y == 0 || z == 0 {
            return Err(invalid(
                path,
                "dims",
                format!("{:?}", self.dims),
                "three counts >= 1",
            ));
        }
        if let ScreenMapping::Tiles {
            tile_size: [tw, th],
        } = self.screen
        {
            if tw == 0 || th == 0 {
                return Err(invalid(
                    path,
                    "screen.tile_size",
                    format!("[{tw}, {th}]"),
                    "sizes >= 1",
                ));
            }
            if width.div_ceil(tw) > x || height.div_ceil(th) > y {
                return Err(invalid(
                    path,
                    "dims",
                    format!("{:?}", self.dims),
                    &format!(
                        "at least {} x {} tiles of {tw} x {th} px to cover {width} x {height}",
                        width.div_ceil(tw),
                        height.div_ceil(th)
                    ),
                ));
            }
        }
        match self.slicing {
            Slicing::None if z != 1 => {
                return Err(invalid(path, "dims[2]", z, "1 with slicing none"));
            }
            Slicing::Linear { near, far }
            | Slicing::Exponential { near, far }
            | Slicing::NearSlice { near, far } => {
                if !(near.is_finite() && far.is_finite() && near > 0.0 && far > near) {
                    return Err(invalid(
                        path,
                        "slicing.near, slicing.far",
                        format!("{near}, {far}"),
                        "0 < near < far, finite",
                    ));
                }
                if matches!(self.slicing, Slicing::NearSlice { .. }) && z < 2 {
                    return Err(invalid(path, "dims[2]", z, "at least 2 with near_slice"));
                }
            }
            Slicing::None => {}
        }
        Ok(())
    }

    /// How many cells (lists) the grid has.
    pub fn cells(&self) -> u64 {
        self.dims.iter().map(|&d| u64::from(d)).product()
    }

    /// The slice of view depth `d`.
    pub fn slice(&self, d: f64) -> u32 {
        let z = self.dims[2];
        let k = match self.slicing {
            Slicing::None => 0.0,
            Slicing::Linear { near, far } => ((d - near) / (far - near) * f64::from(z)).floor(),
            Slicing::Exponential { near, far } => {
                ((d / near).ln() / (far / near).ln() * f64::from(z)).floor()
            }
            Slicing::NearSlice { near, far } => {
                if d < near {
                    0.0
                } else {
                    1.0 + ((d / near).ln() * f64::from(z - 1) / (far / near).ln()).floor()
                }
            }
        };
        if k.is_nan() || k < 0.0 {
            0
        } else {
            (k as u64).min(u64::from(z - 1)) as u32
        }
    }

    /// The cell (index into the offsets) of pixel `(px, py)` at view depth `d`.
    pub fn cell(&self, px: u32, py: u32, d: f64) -> u64 {
        let [nx, ny, _] = self.dims.map(u64::from);
        let (x, y) = match self.screen {
            ScreenMapping::Tiles {
                tile_size: [tw, th],
            } => (u64::from(px / tw), u64::from(py / th)),
            // floor((p + 0.5) n / size) in integers.
            ScreenMapping::Proportional => (
                ((2 * u64::from(px) + 1) * nx) / (2 * u64::from(self.width)),
                ((2 * u64::from(py) + 1) * ny) / (2 * u64::from(self.height)),
            ),
        };
        self.index(x, y, u64::from(self.slice(d)))
    }

    /// The index into the offsets of cell `(x, y, z)`, in the grid's order.
    pub fn index(&self, x: u64, y: u64, z: u64) -> u64 {
        let [nx, ny, nz] = self.dims.map(u64::from);
        match self.order {
            CellOrder::XFastest => (z * ny + y) * nx + x,
            CellOrder::ZFastest => (y * nx + x) * nz + z,
        }
    }

    /// The view depths slice `k` covers, as [`Grid::slice`] maps them: from the eye for the
    /// first slice, open-ended for the last (the lookup clamps).
    pub fn slice_span(&self, k: u32) -> (f64, f64) {
        let z = self.dims[2];
        let (lo, hi) = match self.slicing {
            Slicing::None => (0.0, f64::INFINITY),
            Slicing::Linear { near, far } => {
                let step = (far - near) / f64::from(z);
                (near + step * f64::from(k), near + step * f64::from(k + 1))
            }
            Slicing::Exponential { near, far } => (
                near * (far / near).powf(f64::from(k) / f64::from(z)),
                near * (far / near).powf(f64::from(k + 1) / f64::from(z)),
            ),
            Slicing::NearSlice { near, far } => {
                let e = |j: u32| near * (far / near).powf(f64::from(j) / f64::from(z - 1));
                if k == 0 {
                    (0.0, near)
                } else {
                    (e(k - 1), e(k))
                }
            }
        };
        (
            if k == 0 { 0.0 } else { lo },
            if k + 1 == z { f64::INFINITY } else { hi },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(screen: ScreenMapping, slicing: Slicing, dims: [u32; 3], order: CellOrder) -> Grid {
        Grid {
            format: FORMAT.into(),
            source: String::new(),
            width: 100,
            height: 60,
            dims,
            screen,
            slicing,
            order,
            light_ids: None,
        }
    }

    #[test]
    fn slices_follow_their_formulas_at_the_boundaries() {
        let near_slice = grid(
            ScreenMapping::Proportional,
            Slicing::NearSlice {
                near: 5.0,
                far: 80.0,
            },
            [4, 3, 5],
            CellOrder::ZFastest,
        );
        // [0, 5), then 4 slices splitting [5, 80) by the ratio 2 each, the last open-ended.
        for (d, k) in [
            (0.1, 0),
            (4.999, 0),
            (5.0, 1),
            (9.99, 1),
            (10.01, 2),
            (39.9, 3),
            (40.1, 4),
            (500.0, 4),
        ] {
            assert_eq!(near_slice.slice(d), k, "near_slice at {d}");
        }
        let exp = grid(
            ScreenMapping::Proportional,
            Slicing::Exponential {
                near: 1.0,
                far: 16.0,
            },
            [1, 1, 4],
            CellOrder::XFastest,
        );
        for (d, k) in [(0.5, 0), (1.99, 0), (2.01, 1), (8.01, 3), (100.0, 3)] {
            assert_eq!(exp.slice(d), k, "exponential at {d}");
        }
        let lin = grid(
            ScreenMapping::Proportional,
            Slicing::Linear {
                near: 2.0,
                far: 6.0,
            },
            [1, 1, 4],
            CellOrder::XFastest,
        );
        for (d, k) in [(1.0, 0), (2.99, 0), (3.01, 1), (5.99, 3), (9.0, 3)] {
            assert_eq!(lin.slice(d), k, "linear at {d}");
        }
    }

    #[test]
    fn pixels_map_to_cells_in_either_order() {
        // Bevy's lookup: x = floor((px + 0.5) X / W); 100 px over 4 columns.
        let g = grid(
            ScreenMapping::Proportional,
            Slicing::NearSlice {
                near: 5.0,
                far: 80.0,
            },
            [4, 3, 5],
            CellOrder::ZFastest,
        );
        assert_eq!(g.cell(0, 0, 1.0), 0);
        assert_eq!(g.cell(24, 0, 1.0), 0);
        assert_eq!(g.cell(25, 0, 1.0), 5);
        assert_eq!(g.cell(99, 59, 500.0), (2 * 4 + 3) * 5 + 4);
        let t = grid(
            ScreenMapping::Tiles {
                tile_size: [16, 16],
            },
            Slicing::None,
            [7, 4, 1],
            CellOrder::XFastest,
        );
        assert_eq!(t.cell(17, 33, 3.0), 2 * 7 + 1);
        t.check(Path::new("g.json"), 100, 60).unwrap();
    }

    /// The example of docs/EXPERIMENTS.md is a valid grid for its image.
    #[test]
    fn the_documented_grid_parses() {
        let doc = std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/EXPERIMENTS.md"),
        )
        .unwrap();
        let start = doc.find("```json\n").expect("a ```json block") + "```json\n".len();
        let len = doc[start..].find("```").unwrap();
        let g: Grid = serde_json::from_str(&doc[start..start + len]).unwrap();
        g.check(Path::new("EXPERIMENTS.md"), 1280, 720).unwrap();
        assert_eq!(g.order, CellOrder::ZFastest);
        assert_eq!(g.light_ids.as_deref(), Some("light_ids.npy"));
    }

    #[test]
    fn bad_grids_name_the_field() {
        let p = Path::new("grid.json");
        let short = grid(
            ScreenMapping::Tiles {
                tile_size: [16, 16],
            },
            Slicing::None,
            [6, 4, 1],
            CellOrder::XFastest,
        );
        let e = short.check(p, 100, 60).unwrap_err().to_string();
        assert!(
            e.contains("grid.json") && e.contains("dims") && e.contains("7 x 4"),
            "{e}"
        );
        let e = short.check(p, 640, 360).unwrap_err().to_string();
        assert!(e.contains("width x height = 100 x 60"), "{e}");
        let sliced = grid(
            ScreenMapping::Proportional,
            Slicing::Exponential {
                near: 0.0,
                far: 10.0,
            },
            [4, 4, 8],
            CellOrder::XFastest,
        );
        let e = sliced.check(p, 100, 60).unwrap_err().to_string();
        assert!(e.contains("slicing.near, slicing.far = 0, 10"), "{e}");
        let flat = grid(
            ScreenMapping::Proportional,
            Slicing::None,
            [4, 4, 8],
            CellOrder::XFastest,
        );
        assert!(
            flat.check(p, 100, 60)
                .unwrap_err()
                .to_string()
                .contains("dims[2] = 8")
        );
        let text = r#"{"format": "manylights-lists/1", "width": 100, "height": 60, "dims": [4, 4, 1],
            "screen": {"kind": "hexagons"}, "slicing": {"kind": "none"}, "order": "x_fastest"}"#;
        let e = serde_json::from_str::<Grid>(text).unwrap_err().to_string();
        assert!(e.contains("hexagons") && e.contains("tiles"), "{e}");
    }
}
