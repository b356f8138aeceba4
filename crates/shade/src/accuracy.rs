//! Image error of a render against a reference: maximum absolute error, RMSE and PSNR on the
//! HDR values, and mean FLIP (NVIDIA's perceptual metric, through `nv-flip`) on the tonemapped
//! 8-bit images.
//!
//! PSNR is `10 log10(peak^2 / MSE)` with `peak` the reference's largest RGB value and MSE over
//! every RGB channel of every pixel; identical images give `+inf`. The peak of a many-light
//! image is a hot spot next to a light (the falloff reaches `1 / D_MIN^2 = 10^4` times a
//! light's intensity there), thousands of times a typical pixel, so PSNR reads errors against
//! that hot spot: the reports shipped before read 47-63 dB against infinite range for images
//! that hold 1% to 37% of its energy (docs/reports/infinite-range measures the energy). Against
//! infinite range, read FLIP, RMSE and the energy error.
//!
//! The energy error is the signed mean of `(L_test - L_ref) / L_ref` over lit pixels (covered,
//! with reference luminance `L_ref` at least [`LIT_FRACTION`] of the covered pixels' mean;
//! luminance with Rec. 709's weights): negative where the test image is darker, the bias a
//! radius cut-off always has.
//!
//! FLIP compares tonemapped images, so it depends on the exposure. A fixed exposure of 1 fits
//! the windowed images of the shipped experiments but not their infinite-range references, whose
//! light grows with the lit region: at exposure 1 their typical pixel maps near white, where
//! the tonemapper's slope is small, and any difference is exaggerated or hidden depending on the
//! scene. [`exposure_of`] takes the exposure from the reference itself instead (Reinhard et al.
//! 2002's key: the log-average luminance of its covered pixels mapped to 0.18), so both images
//! are seen as a viewer adapted to the reference would see them; [`compare_adapted`] uses it.

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
    /// Signed mean relative luminance error over lit pixels (see the module docs).
    pub energy_error: f64,
    /// The exposure both images were tonemapped with for FLIP.
    pub exposure: f32,
}

/// Lit pixels (for the energy error) have at least this fraction of the covered pixels' mean
/// reference luminance: darker ones would weigh a tiny denominator's noise.
pub const LIT_FRACTION: f64 = 1e-3;

/// The key the reference's log-average luminance maps to (Reinhard et al. 2002).
pub const KEY: f64 = 0.18;

/// Rec. 709 luminance of an RGB texel.
pub fn luminance(t: [f32; 4]) -> f64 {
    manylights_scene::light::luminance(glam::Vec3::new(t[0], t[1], t[2]))
}

/// The exposure adapted to `reference`: [`KEY`] over the log-average luminance of its covered
/// pixels (alpha > 0), `exp(mean(ln(1e-6 + L)))`; 1 where nothing is covered or lit.
pub fn exposure_of(reference: &HdrImage) -> f32 {
    let (mut sum, mut n) = (0.0f64, 0usize);
    for t in &reference.data {
        if t[3] > 0.0 {
            sum += (1e-6 + luminance(*t).max(0.0)).ln();
            n += 1;
        }
    }
    if n == 0 {
        return 1.0;
    }
    let avg = (sum / n as f64).exp();
    if avg > 2e-6 { (KEY / avg) as f32 } else { 1.0 }
}

/// [`compare`] at the exposure adapted to the reference ([`exposure_of`]).
pub fn compare_adapted(test: &HdrImage, reference: &HdrImage) -> ImageError {
    compare(test, reference, exposure_of(reference))
}

/// The signed mean relative luminance error of `test` over the lit pixels of `reference`.
pub fn energy_error(test: &HdrImage, reference: &HdrImage) -> f64 {
    let covered: Vec<(f64, f64)> = test
        .data
        .iter()
        .zip(&reference.data)
        .filter(|(_, r)| r[3] > 0.0)
        .map(|(t, r)| (luminance(*t), luminance(*r)))
        .collect();
    let mean = covered.iter().map(|c| c.1).sum::<f64>() / covered.len().max(1) as f64;
    let lit: Vec<f64> = covered
        .iter()
        .filter(|c| c.1 > 0.0 && c.1 >= LIT_FRACTION * mean)
        .map(|(t, r)| (t - r) / r)
        .collect();
    if lit.is_empty() {
        0.0
    } else {
        lit.iter().sum::<f64>() / lit.len() as f64
    }
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
        energy_error: energy_error(test, reference),
        exposure,
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
