//! Stochastic light culling (Tokuyoshi and Harada, "Stochastic Light Culling", JCGT 5(1),
//! 2016): each light gets a random range each frame, drawn by Russian roulette on its falloff,
//! so that culling by range stays conservative while the image is an unbiased estimate of the
//! infinite-range one (no cut-off), at the price of noise.
//!
//! With one uniform `xi` per light and frame, shared by every pixel, and `f(d) = 1 / d^2` (with
//! the project's `D_MIN`), the light is evaluated at distance `d` iff `d < r = 1 / sqrt(alpha *
//! xi)`, which happens with probability `p(d) = min(f(d) / alpha, 1)`, and then contributes
//! `f / p = max(f(d), alpha)`: the expectation is `f(d)` at every distance.
//!
//! `alpha` follows from an error bound. One light's falloff estimate has variance
//! `f (alpha - f) <= alpha^2 / 4`, so its standard deviation is at most `alpha / 2`. What that
//! deviation is bounded in is [`StochasticBound`]:
//! - `Light` (the default), as Tokuyoshi and Harada do: the light's own incident contribution,
//!   `exposure * intensity * max(colour) * falloff`, whatever the surface: `error` bounds the
//!   standard deviation of one light's exposed irradiance at normal incidence, so
//!   `alpha = 2 error / (exposure * intensity * max(colour))`. The lists depend on the lights,
//!   never on the materials.
//! - `Albedo`: the radiance it reflects off a surface that spreads the scene's largest
//!   directional albedo diffusely (`scale = albedo_max / pi`, [`crate::brdf::albedo_max`]: at
//!   most about 2 for GGX and the clear coat, finite for every lobe). Exact as a bound on
//!   Lambertian pixels; a glossy lobe's peak exceeds it where the lobe is narrower than the
//!   hemisphere, its average over light directions does not.
//!
//! A bound through the materials' peak BRDF (GGX's `1 / (2 pi alpha^3)`, about 2e7 at the
//! roughness floor) is not offered: it made every range the whole scene (3,000 of 3,000 lights a
//! pixel in the city). Either way `alpha = 2 error / (exposure * intensity * max(colour) *
//! scale)`, clamped to at most `1 / D_MIN^2` (the falloff's largest value: above it the estimate
//! would not be unbiased inside `D_MIN`); the estimate is unbiased whatever `alpha` is, so the
//! bound only trades noise for list length.
//!
//! `xi` is `(h + 0.5) / 2^24` for a 24-bit hash `h` of the seed, the frame and the light: never
//! 0, so every range is finite, the longest `2^12.5 / sqrt(alpha)` (about 5,800 times the range
//! at `xi = 1`). The draw is exact on the midpoints of 2^24 equal steps: `P(xi <= x)` differs
//! from `x` by at most `2^-25`, a bias below `2^-25` of one light's largest term (documented,
//! not measurable at any error bound a report uses).
//!
//! Stratified draws ([`StochasticDraw::Stratified`], the default): the lights' `xi` of one frame
//! are not independent but one randomly shifted rank-1 lattice over the lights in spatial
//! order: light `i` with stratum `s_i` (its rank along a Morton curve through the lights'
//! bounding box, [`strata`]) draws `xi = frac(u + s_i phi)`, `phi` the golden ratio's
//! fraction (24 bits, [`PHI_BITS`]) and `u` one hash of the seed and frame. Each light's `xi`
//! is still uniform, so every light's estimate and the image stay unbiased and the culled
//! spheres keep their meaning; but neighbouring lights draw evenly spread numbers, so of the
//! many far lights a pixel sees at similar distances almost exactly the expected fraction
//! reaches it, instead of a binomial count. That is stratified Russian roulette over the
//! lights (Tokuyoshi and Harada's hierarchical Russian roulette, TOG 38(4), 2019, correlates
//! its draws over a tree of lights for the same reason). Strata come from the lights as
//! generated; lights that move keep them (still unbiased, less stratified).
//! [`StochasticDraw::Independent`] hashes each light and frame apart, as the 2016 paper does.
//!
//! Interleaved sampling (Tokuyoshi and Harada, CGF 36(4), 2017; Keller and Heidrich 2001):
//! with `interleave: n` (n >= 2) the pixels fall into `n x n` classes by their coordinates
//! modulo n ([`pixel_class`]), and each light draws one `xi` per class each frame
//! ([`class_xi`], from a 24-bit [`key`] of the seed, frame and light). A pixel evaluates the
//! light out to its own class's range, so neighbouring pixels see independent draws and the
//! noise is spread over the `n x n` block instead of shared by the whole image. Culling runs
//! over one sphere a light, the longest of its classes' ranges (the smallest `xi`); the exact
//! oracle counts false negatives against that sphere, so it is conservative for every class.
//! The longest of `n^2` draws is about `n` times the range of one (the smallest of `n^2`
//! uniforms has mean `1 / (n^2 + 1)`), so lists grow with `n`: interleaving trades list length
//! for noise that a spatial filter (the eye, FLIP's contrast sensitivity, a denoiser) averages.
//! The classes draw independent hashes whatever the [`StochasticDraw`].
//!
//! The same draw and ranges run on the GPU (`shaders/lights/stochastic.wgsl`, pass
//! `lights.stochastic`); [`shade`] is the estimate in f64 that the tests hold the GPU to.

use glam::DVec3;

use crate::light::D_MIN;
use crate::motion::pcg;
use crate::{Light, Material};

/// Bits of the uniform number drawn for each light and frame.
pub const XI_BITS: u32 = 24;

/// The golden ratio's fraction `(sqrt(5) - 1) / 2` in [`XI_BITS`] bits, rounded to odd so that
/// `s -> s PHI_BITS mod 2^24` is a permutation of the strata.
pub const PHI_BITS: u32 = 10_368_889;

/// The largest `n` of interleaved sampling over `n x n` pixel classes.
pub const INTERLEAVE_MAX: u32 = 8;

/// The uniform number in (0, 1) of a 32-bit hash: its top [`XI_BITS`] bits, at the midpoint
/// of their step.
pub(crate) fn unit(h: u32) -> f32 {
    ((h >> (32 - XI_BITS)) as f32 + 0.5) / (1u32 << XI_BITS) as f32
}

/// The uniform number of light `index` at frame `frame` under seed `seed`: in (0, 1), never 0.
/// The GPU's `stochastic_xi` computes the same bits.
pub fn xi(seed: u32, frame: u32, index: u32) -> f32 {
    unit(pcg(index ^ pcg(frame ^ pcg(seed))))
}

/// The stratified draw of the light with stratum `stratum` at frame `frame` under seed `seed`:
/// `frac(u + stratum phi)` on [`XI_BITS`] bits, `u` the top bits of one hash of the seed and
/// frame. In (0, 1), never 0; uniform for every stratum. The GPU's `draw` computes the same
/// bits.
pub fn stratified_xi(seed: u32, frame: u32, stratum: u32) -> f32 {
    let u = pcg(frame ^ pcg(seed)) >> (32 - XI_BITS);
    let mask = (1u32 << XI_BITS) - 1;
    let bits = u.wrapping_add(stratum.wrapping_mul(PHI_BITS)) & mask;
    (bits as f32 + 0.5) / (1u32 << XI_BITS) as f32
}

/// Each light's stratum for [`StochasticDraw::Stratified`]: its rank along a Morton curve
/// (21 bits an axis) through the bounding box of the lights' positions, ties in light order.
/// A permutation of `0..lights.len()`.
pub fn strata(lights: &[Light]) -> Vec<u32> {
    let (lo, hi) = lights.iter().fold(
        (glam::Vec3::splat(f32::MAX), glam::Vec3::splat(f32::MIN)),
        |(lo, hi), l| (lo.min(l.position), hi.max(l.position)),
    );
    let cells = ((1u32 << 21) - 1) as f32;
    let scale = cells / (hi - lo).max(glam::Vec3::splat(1e-20));
    let mut order: Vec<(u64, u32)> = lights
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let q = ((l.position - lo) * scale).clamp(glam::Vec3::ZERO, glam::Vec3::splat(cells));
            let code = spread(q.x as u64) | spread(q.y as u64) << 1 | spread(q.z as u64) << 2;
            (code, i as u32)
        })
        .collect();
    order.sort_unstable();
    let mut ranks = vec![0u32; lights.len()];
    for (rank, &(_, i)) in order.iter().enumerate() {
        ranks[i as usize] = rank as u32;
    }
    ranks
}

/// The low 21 bits of `x` spread to every third bit.
fn spread(x: u64) -> u64 {
    let mut x = x & 0x1f_ffff;
    x = (x | x << 32) & 0x1f_0000_0000_ffff;
    x = (x | x << 16) & 0x1f_0000_ff00_00ff;
    x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
    x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
    x = (x | x << 2) & 0x1249_2492_4924_9249;
    x
}

/// How one frame's numbers are drawn across the lights (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum StochasticDraw {
    /// One shifted lattice over the lights in spatial order (the default).
    #[default]
    Stratified,
    /// One independent hash a light and frame (Tokuyoshi and Harada 2016).
    Independent,
}

impl StochasticDraw {
    /// The name in parameters and the CLI: `stratified` or `independent`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Stratified => "stratified",
            Self::Independent => "independent",
        }
    }
}

/// The 24-bit key of light `index` at frame `frame` under seed `seed` from which its
/// interleaved classes draw ([`class_xi`]): the same hash as [`xi`]'s, its top 24 bits.
pub fn key(seed: u32, frame: u32, index: u32) -> u32 {
    pcg(index ^ pcg(frame ^ pcg(seed))) >> 8
}

/// The uniform number in (0, 1) of pixel class `class` (< 256) for a light with `key`: the
/// hash of the key with the class in its top byte (distinct inputs for distinct pairs). The
/// GPU's `light_range` computes the same bits.
pub fn class_xi(key: u32, class: u32) -> f32 {
    unit(pcg(key ^ (class << 24)))
}

/// The class of pixel `(x, y)` among `n x n`: `x mod n + n (y mod n)`.
pub fn pixel_class(x: u32, y: u32, n: u32) -> u32 {
    x % n + n * (y % n)
}

/// What the error bound of stochastic light culling bounds (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum StochasticBound {
    /// One light's exposed incident contribution, independent of the materials (the default).
    #[default]
    Light,
    /// The radiance one light reflects off a surface spreading the scene's largest directional
    /// albedo diffusely ([`crate::brdf::albedo_max`] over pi).
    Albedo,
}

impl StochasticBound {
    /// The name in parameters and the CLI: `light` or `albedo`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Light => "light",
            Self::Albedo => "albedo",
        }
    }

    /// The factor between one light's `intensity * max(colour) * falloff` and what `error`
    /// bounds: 1 for `Light`; for `Albedo` the largest [`crate::brdf::albedo_max`] of
    /// `materials` over pi (a white Lambertian surface's `1 / pi` where `materials` is empty).
    pub fn scale(self, materials: &[Material]) -> f32 {
        match self {
            Self::Light => 1.0,
            Self::Albedo => {
                (materials
                    .iter()
                    .map(|m| crate::brdf::albedo_max(&m.brdf, m.base_color.as_dvec3()))
                    .reduce(f64::max)
                    .unwrap_or(1.0)
                    / std::f64::consts::PI) as f32
            }
        }
    }
}

/// The parameters a frame's ranges are drawn with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StochasticParams {
    /// The bound on one light's standard deviation at a pixel, in exposed radiance.
    pub error: f32,
    /// The exposure the error is measured at (radiance is multiplied by it before tonemapping).
    pub exposure: f32,
    /// [`StochasticBound::scale`] of the bound and the scene's materials.
    pub scale: f32,
    /// The seed of every draw.
    pub seed: u32,
    /// Interleaved sampling over `interleave x interleave` pixel classes; 1: none (every pixel
    /// shares one draw a light).
    pub interleave: u32,
    /// How a frame's numbers are drawn across the lights (without interleaving).
    pub draw: StochasticDraw,
}

impl StochasticParams {
    /// The light's `alpha`, in f32 as the GPU computes it.
    pub fn alpha(&self, light: &Light) -> f32 {
        let scale = self.exposure * light.intensity * light.color.max_element() * self.scale;
        let max = (1.0 / (D_MIN * D_MIN)) as f32;
        if scale > 0.0 {
            (2.0 * self.error / scale).min(max)
        } else {
            max
        }
    }

    /// The range of a light with `alpha` for the draw `xi`: `1 / sqrt(alpha * xi)`.
    pub fn range(alpha: f32, xi: f32) -> f32 {
        1.0 / (alpha * xi).sqrt()
    }

    /// Light `index` (of the scene's light buffer) with stratum `stratum` ([`strata`] of the
    /// drawn lights; unused by independent and interleaved draws) as culled at frame `frame`:
    /// its range for the frame in `radius` (with interleaving, the longest of its classes'
    /// ranges), and its alpha.
    pub fn at_frame(&self, light: &Light, index: u32, stratum: u32, frame: u32) -> (Light, f32) {
        let xi = if self.interleave > 1 {
            let k = key(self.seed, frame, index);
            (0..self.interleave * self.interleave)
                .map(|c| class_xi(k, c))
                .fold(1.0f32, f32::min)
        } else if self.draw == StochasticDraw::Stratified {
            stratified_xi(self.seed, frame, stratum)
        } else {
            xi(self.seed, frame, index)
        };
        self.with_xi(light, xi)
    }

    /// `light` with the range of the draw `xi` in `radius`, and its alpha.
    fn with_xi(&self, light: &Light, xi: f32) -> (Light, f32) {
        let alpha = self.alpha(light);
        (
            Light {
                radius: Self::range(alpha, xi),
                ..*light
            },
            alpha,
        )
    }

    /// Light `index` (stratum `stratum`) as shaded at frame `frame` by a pixel of class `class`
    /// (ignored without interleaving): its class's range in `radius`, and its alpha.
    pub fn at_pixel(
        &self,
        light: &Light,
        index: u32,
        stratum: u32,
        frame: u32,
        class: u32,
    ) -> (Light, f32) {
        if self.interleave <= 1 {
            return self.at_frame(light, index, stratum, frame);
        }
        self.with_xi(light, class_xi(key(self.seed, frame, index), class))
    }

    /// The word the GPU keeps in a drawn light's `interleave`: 0 without interleaving,
    /// otherwise `n << 24 | key` (`light_range` in `shaders/common/light.wgsl` reads it).
    pub fn interleave_word(&self, index: u32, frame: u32) -> u32 {
        if self.interleave > 1 {
            self.interleave << 24 | key(self.seed, frame, index)
        } else {
            0
        }
    }
}

/// The stochastic estimate at surface point `p` (unit normal `n`, unit direction `v` to the
/// viewer) in f64: each light with its frame's range in `radius` and its alpha in `alphas`,
/// shaded with `max(1 / d^2, alpha)` inside the range. The CPU twin of the GPU's
/// `light_attenuation` for lights of stochastic culling's falloff (`LIGHT_FALLOFF_STOCHASTIC`).
pub fn shade(
    p: DVec3,
    n: DVec3,
    v: DVec3,
    material: &Material,
    lights: &[Light],
    alphas: &[f32],
) -> DVec3 {
    crate::light::shade_with(p, n, v, material, lights, |k, light, d| {
        if d < f64::from(light.radius) {
            (1.0 / (d * d).max(D_MIN * D_MIN)).max(f64::from(alphas[k]))
        } else {
            0.0
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn xi_is_in_the_open_unit_interval_and_uniform() {
        let n = 1 << 16;
        let mut mean = 0.0f64;
        for i in 0..n {
            let x = xi(7, 3, i);
            assert!(x > 0.0 && x < 1.0, "{x}");
            mean += f64::from(x);
        }
        mean /= f64::from(n);
        // The mean of n uniform draws: 0.5 within 5 standard errors (1 / sqrt(12 n)).
        assert!(
            (mean - 0.5).abs() < 5.0 / (12.0 * f64::from(n)).sqrt(),
            "{mean}"
        );
        assert_ne!(xi(7, 3, 0), xi(7, 4, 0), "frames draw apart");
        assert_ne!(xi(7, 3, 0), xi(8, 3, 0), "seeds draw apart");
    }

    #[test]
    fn the_range_passes_the_roulette_exactly_where_the_falloff_beats_alpha_xi() {
        let light = Light::point(Vec3::ZERO, 1.0, Vec3::ONE, 4.0);
        let params = StochasticParams {
            error: 0.01,
            exposure: 1.0,
            scale: StochasticBound::Light.scale(&[]),
            seed: 1,
            interleave: 1,
            draw: StochasticDraw::Independent,
        };
        let alpha = params.alpha(&light);
        // 2 * 0.01 / (4 * 1 * 1): the light's own contribution.
        let expect = 0.02 / 4.0;
        assert!((f64::from(alpha) - expect).abs() < 1e-6 * expect, "{alpha}");
        for k in 0..100 {
            let (l, _) = params.at_frame(&light, 0, 0, k);
            let x = f64::from(xi(1, k, 0));
            let r = f64::from(l.radius);
            // At the range, 1 / r^2 = alpha * xi.
            assert!((1.0 / (r * r) - f64::from(alpha) * x).abs() < 1e-5 * f64::from(alpha) * x);
        }
    }

    #[test]
    fn the_estimate_is_unbiased_over_many_frames() {
        // One light seen from points at several distances: the mean of the estimate over
        // many frames against 1 / d^2 times the BRDF, within 5 standard errors.
        let light = Light::point(DVec3::new(0.0, 1.0, 0.0).as_vec3(), 1.0, Vec3::ONE, 1.0);
        let m = Material::new(Vec3::splat(0.5), 0.0);
        let params = StochasticParams {
            error: 0.05,
            exposure: 1.0,
            scale: StochasticBound::Albedo.scale(&[m]),
            seed: 3,
            interleave: 1,
            draw: StochasticDraw::Independent,
        };
        let (n, v) = (DVec3::Y, DVec3::Y);
        for (params, stratum, x) in [StochasticDraw::Independent, StochasticDraw::Stratified]
            .into_iter()
            .flat_map(|draw| {
                [(0, 0.0), (5, 0.5), (1234, 2.0), (77_777, 6.0)]
                    .map(|(s, x)| (StochasticParams { draw, ..params }, s, x))
            })
        {
            let p = DVec3::new(x, 0.0, 0.0);
            let exact = crate::light::shade(p, n, v, &m, &[light], crate::light::Range::Infinite).x;
            let frames = 20_000;
            let (mut s, mut s2) = (0.0f64, 0.0f64);
            for f in 0..frames {
                let (l, a) = params.at_frame(&light, 0, stratum, f);
                let e = shade(p, n, v, &m, &[l], &[a]).x;
                s += e;
                s2 += e * e;
            }
            let mean = s / f64::from(frames);
            let var = (s2 / f64::from(frames) - mean * mean).max(0.0);
            let se = (var / f64::from(frames)).sqrt();
            assert!(
                (mean - exact).abs() <= 5.0 * se + 1e-6 * exact,
                "{:?}, x = {x}: mean {mean} vs {exact} (standard error {se})",
                params.draw
            );
        }
    }

    #[test]
    fn strata_follow_space_and_stratified_draws_spread_evenly_over_them() {
        // Lights along a line, listed out of order: their strata are their order along it.
        let xs = [5.0, -3.0, 0.5, 9.0, -7.0, 2.0];
        let lights: Vec<Light> = xs
            .iter()
            .map(|&x| Light::point(Vec3::new(x, 1.0, 2.0), 1.0, Vec3::ONE, 1.0))
            .collect();
        assert_eq!(strata(&lights), vec![4, 1, 2, 5, 0, 3]);
        // One frame's draws over 10,000 strata: every interval [0, x) holds x of them within
        // a few (a lattice's discrepancy), where independent draws stray by about sqrt(n x).
        let n = 10_000u32;
        for frame in [0, 1, 17] {
            let mut draws: Vec<f32> = (0..n).map(|s| stratified_xi(3, frame, s)).collect();
            draws.sort_by(f32::total_cmp);
            let worst = draws
                .iter()
                .enumerate()
                .map(|(k, &x)| (f64::from(x) * f64::from(n) - k as f64).abs())
                .fold(0.0, f64::max);
            assert!(worst < 5.0, "frame {frame}: discrepancy {worst} draws");
        }
        // Every stratum's draw is uniform over frames.
        for stratum in [0, 1, 999, 1 << 20] {
            let frames = 20_000;
            let mean = (0..frames)
                .map(|f| f64::from(stratified_xi(3, f, stratum)))
                .sum::<f64>()
                / f64::from(frames);
            let bound = 5.0 / (12.0 * f64::from(frames)).sqrt();
            assert!((mean - 0.5).abs() < bound, "stratum {stratum}: {mean}");
        }
    }

    #[test]
    fn stratified_draws_cut_the_variance_of_many_far_lights() {
        // 4,000 lights in a 4 m box 20 m from the point: each reaches it with a small
        // probability, so the independent count is binomial; the stratified one is close to
        // its mean. The variance over frames falls by far more than half, the mean stays.
        let mut rng = 0x9e37_79b9u32;
        let mut unit = || {
            rng = pcg(rng);
            (rng >> 8) as f32 / (1u32 << 24) as f32
        };
        let lights: Vec<Light> = (0..4000)
            .map(|_| {
                let p = Vec3::new(unit() * 4.0, unit() * 4.0, 20.0 + unit() * 4.0);
                Light::point(p, 1.0, Vec3::ONE, 1.0)
            })
            .collect();
        let strata = strata(&lights);
        let m = Material::new(Vec3::splat(0.5), 0.0);
        let (p, n, v) = (DVec3::new(2.0, 2.0, 0.0), DVec3::Z, DVec3::Z);
        let exact = crate::light::shade(p, n, v, &m, &lights, crate::light::Range::Infinite).x;
        let stats = |draw| {
            let params = StochasticParams {
                error: 0.05,
                exposure: 1.0,
                scale: 1.0,
                seed: 11,
                interleave: 1,
                draw,
            };
            let frames = 400;
            let (mut s, mut s2) = (0.0, 0.0);
            for f in 0..frames {
                let (drawn, alphas): (Vec<Light>, Vec<f32>) = lights
                    .iter()
                    .zip(&strata)
                    .enumerate()
                    .map(|(i, (l, &st))| params.at_frame(l, i as u32, st, f))
                    .unzip();
                let e = shade(p, n, v, &m, &drawn, &alphas).x;
                s += e;
                s2 += e * e;
            }
            let mean = s / f64::from(frames);
            (mean, s2 / f64::from(frames) - mean * mean)
        };
        let (mean_i, var_i) = stats(StochasticDraw::Independent);
        let (mean_s, var_s) = stats(StochasticDraw::Stratified);
        assert!(
            var_s < 0.25 * var_i,
            "variance {var_s} stratified vs {var_i}"
        );
        for mean in [mean_i, mean_s] {
            assert!((mean / exact - 1.0).abs() < 0.05, "mean {mean} vs {exact}");
        }
    }

    #[test]
    fn interleaved_classes_draw_apart_and_the_culled_range_covers_every_class() {
        let light = Light::point(Vec3::ZERO, 1.0, Vec3::ONE, 4.0);
        let params = StochasticParams {
            error: 0.01,
            exposure: 1.0,
            scale: StochasticBound::Light.scale(&[]),
            seed: 9,
            interleave: 3,
            draw: StochasticDraw::Stratified,
        };
        assert_eq!(pixel_class(4, 5, 3), 1 + 3 * 2);
        let (mut mean, mut n) = (0.0f64, 0);
        for frame in 0..200 {
            let (culled, _) = params.at_frame(&light, 7, 0, frame);
            let ranges: Vec<f32> = (0..9)
                .map(|c| params.at_pixel(&light, 7, 0, frame, c).0.radius)
                .collect();
            let longest = ranges.iter().copied().fold(0.0f32, f32::max);
            assert_eq!(culled.radius, longest, "frame {frame}: the culled sphere");
            assert!(
                ranges.windows(2).any(|w| w[0] != w[1]),
                "classes draw apart"
            );
            for c in 0..9 {
                mean += f64::from(class_xi(key(9, frame, 7), c));
                n += 1;
            }
            let word = params.interleave_word(7, frame);
            assert_eq!((word >> 24, word & 0xff_ffff), (3, key(9, frame, 7)));
        }
        mean /= f64::from(n);
        assert!(
            (mean - 0.5).abs() < 5.0 / (12.0 * f64::from(n)).sqrt(),
            "{mean}"
        );
        let plain = StochasticParams {
            interleave: 1,
            ..params
        };
        assert_eq!(plain.interleave_word(7, 0), 0);
        assert_eq!(
            plain.at_pixel(&light, 7, 0, 0, 5),
            plain.at_frame(&light, 7, 0, 0)
        );
    }
}
