//! HDR images, tonemapping and atomic file output.
//!
//! Tonemapping (for PNGs and, later, FLIP): `c' = e*c / (1 + e*c)` per channel (Reinhard) with
//! exposure `e`, then the sRGB transfer function, rounded to 8 bits.

use std::io::Write;
use std::path::Path;

/// An RGBA f32 image, rows from the top.
#[derive(Clone, Debug, PartialEq)]
pub struct HdrImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height` RGBA texels.
    pub data: Vec<[f32; 4]>,
}

/// A running sum of same-sized images in f64, for the mean of frames accumulated (a static
/// view under stochastic light culling).
#[derive(Clone, Debug, Default)]
pub struct ImageSum {
    sum: Vec<[f64; 3]>,
    first: Option<HdrImage>,
    count: u32,
}

impl ImageSum {
    /// Adds `image` (of the first image's size: a mismatch is a caller's bug and panics).
    pub fn add(&mut self, image: &HdrImage) {
        match &self.first {
            None => {
                self.sum = vec![[0.0; 3]; image.data.len()];
                self.first = Some(image.clone());
            }
            Some(f) => assert_eq!(
                (f.width, f.height),
                (image.width, image.height),
                "images of one sum share a size"
            ),
        }
        for (a, t) in self.sum.iter_mut().zip(&image.data) {
            for ch in 0..3 {
                a[ch] += f64::from(t[ch]);
            }
        }
        self.count += 1;
    }

    /// Images added.
    pub fn count(&self) -> u32 {
        self.count
    }

    /// The mean image, with the first image's alpha (coverage); `None` before any image.
    pub fn mean(&self) -> Option<HdrImage> {
        self.mean_over(self.first.as_ref()?)
    }

    /// The mean image with `coverage`'s alpha (of the same size: a mismatch is a caller's bug
    /// and panics); `None` before any image.
    pub fn mean_over(&self, coverage: &HdrImage) -> Option<HdrImage> {
        self.first.as_ref()?;
        assert_eq!(
            self.sum.len(),
            coverage.data.len(),
            "coverage of the sum's size"
        );
        let n = f64::from(self.count);
        Some(HdrImage {
            width: coverage.width,
            height: coverage.height,
            data: self
                .sum
                .iter()
                .zip(&coverage.data)
                .map(|(s, f)| {
                    [
                        (s[0] / n) as f32,
                        (s[1] / n) as f32,
                        (s[2] / n) as f32,
                        f[3],
                    ]
                })
                .collect(),
        })
    }
}

/// Errors of image output.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// A file could not be written.
    #[error("cannot write {path}: {message}")]
    Write {
        /// The destination.
        path: String,
        /// Why.
        message: String,
    },
}

impl HdrImage {
    /// From tightly packed `Rgba32Float` bytes.
    pub fn from_bytes(width: u32, height: u32, bytes: &[u8]) -> Self {
        Self {
            width,
            height,
            data: bytemuck::pod_collect_to_vec(bytes),
        }
    }

    /// The texel at `(x, y)`.
    pub fn at(&self, x: u32, y: u32) -> [f32; 4] {
        self.data[(y * self.width + x) as usize]
    }

    /// Number of texels with a NaN or infinite channel.
    pub fn non_finite_count(&self) -> usize {
        self.data
            .iter()
            .filter(|t| t.iter().any(|c| !c.is_finite()))
            .count()
    }

    /// Largest RGB channel value.
    pub fn peak(&self) -> f32 {
        self.data
            .iter()
            .flat_map(|t| t[..3].iter().copied())
            .fold(0.0, f32::max)
    }

    /// 8-bit sRGB of the tonemapped image.
    pub fn tonemap(&self, exposure: f32) -> image::RgbImage {
        let map = |c: f32| {
            let x = (c * exposure).max(0.0);
            let x = x / (1.0 + x);
            let s = if x <= 0.003_130_8 {
                12.92 * x
            } else {
                1.055 * x.powf(1.0 / 2.4) - 0.055
            };
            (s * 255.0).round().clamp(0.0, 255.0) as u8
        };
        image::RgbImage::from_fn(self.width, self.height, |x, y| {
            let t = self.at(x, y);
            image::Rgb([map(t[0]), map(t[1]), map(t[2])])
        })
    }

    /// Writes a tonemapped PNG, atomically.
    pub fn write_png(&self, path: &Path, exposure: f32) -> Result<(), OutputError> {
        let img = self.tonemap(exposure);
        write_atomic(path, |f| {
            img.write_to(f, image::ImageFormat::Png)
                .map_err(|e| e.to_string())
        })
    }

    /// Writes the RGB channels as a 32-bit float OpenEXR file, atomically.
    pub fn write_exr(&self, path: &Path) -> Result<(), OutputError> {
        let rgb: Vec<f32> = self.data.iter().flat_map(|t| [t[0], t[1], t[2]]).collect();
        let img = image::Rgb32FImage::from_raw(self.width, self.height, rgb).expect("size matches");
        write_atomic(path, |f| {
            image::DynamicImage::ImageRgb32F(img)
                .write_to(f, image::ImageFormat::OpenExr)
                .map_err(|e| e.to_string())
        })
    }
}

/// Writes `path` through a temporary file in the same directory and renames it into place, so
/// a failure never leaves a half-written file. Creates the parent directory if needed. The file
/// gets the mode any new file gets (0666 less the umask).
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut std::io::BufWriter<&mut std::fs::File>) -> Result<(), String>,
) -> Result<(), OutputError> {
    let err = |message: String| OutputError::Write {
        path: path.display().to_string(),
        message,
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    std::fs::create_dir_all(dir).map_err(|e| err(e.to_string()))?;
    // A temporary file is private (0600) by default; what is written here is the program's
    // output, so it follows the umask as any other program's files do.
    let mut builder = tempfile::Builder::new();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let mut tmp = builder.tempfile_in(dir).map_err(|e| err(e.to_string()))?;
    {
        let mut w = std::io::BufWriter::new(tmp.as_file_mut());
        write(&mut w).map_err(err)?;
        w.flush().map_err(|e| err(e.to_string()))?;
    }
    tmp.persist(path).map_err(|e| err(e.error.to_string()))?;
    Ok(())
}
