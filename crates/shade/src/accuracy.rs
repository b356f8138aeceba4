//! Image error of a render against a reference: maximum absolute error, RMSE and PSNR on the
//! HDR values, and mean FLIP (NVIDIA's perceptual metric, through `nv-flip`) on the tonemapped
//! 8-bit images.
//!
//! PSNR is `10 log10(peak^2 / MSE)` with `peak` the reference's largest RGB value and MSE over
//! every RGB channel of every pixel; identical images give `+inf`.

use image::RgbImage;

use crate::HdrImage;

/// Error of one image against a reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageError {
    /// Largest absolute difference of any RGB channel.
    pub max_abs_error: f64,
    /// Root mean square difference over every RGB channel.
    pub rmse: f64,
    /// Peak signal-to-noise ratio in dB (infinite when identical).
    pub psnr_db: f64,
    /// Mean FLIP error of the tonemapped images, in [0, 1].
    pub flip_mean: f64,
    /// The reference's largest RGB value (the PSNR peak).
    pub peak: f64,
}

/// Compares `test` with `reference` (same size), tonemapping both with `exposure` for FLIP.
pub fn compare(test: &HdrImage, reference: &HdrImage, exposure: f32) -> ImageError {
    assert_eq!(
        (test.width, test.height),
        (reference.width, reference.height),
        "image sizes differ"
    );
    let mut max_abs = 0.0f64;
    let mut sq = 0.0f64;
    for (a, b) in test.data.iter().zip(&reference.data) {
        for c in 0..3 {
            let d = f64::from(a[c]) - f64::from(b[c]);
            max_abs = max_abs.max(d.abs());
            sq += d * d;
        }
    }
    let n = (test.data.len() * 3).max(1) as f64;
    let mse = sq / n;
    let peak = f64::from(reference.peak());
    let psnr_db = if mse == 0.0 {
        f64::INFINITY
    } else {
        10.0 * (peak * peak / mse).log10()
    };
    let map = flip_error(test, reference, exposure);
    let flip_mean = f64::from(nv_flip::FlipPool::from_image(&map).mean());
    ImageError {
        max_abs_error: max_abs,
        rmse: mse.sqrt(),
        psnr_db,
        flip_mean,
        peak,
    }
}

fn flip_error(test: &HdrImage, reference: &HdrImage, exposure: f32) -> nv_flip::FlipImageFloat {
    let to_flip = |img: &HdrImage| {
        let rgb = img.tonemap(exposure);
        nv_flip::FlipImageRgb8::with_data(img.width, img.height, rgb.as_raw())
    };
    nv_flip::flip(
        to_flip(reference),
        to_flip(test),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    )
}

/// The FLIP error map, coloured with FLIP's magma look-up table (black: no error).
pub fn flip_map(test: &HdrImage, reference: &HdrImage, exposure: f32) -> RgbImage {
    let map = flip_error(test, reference, exposure).apply_color_lut(&nv_flip::magma_lut());
    RgbImage::from_raw(test.width, test.height, map.to_vec())
        .expect("FLIP map has the image's size")
}
