//! Stochastic shadows' estimator, the CPU twin of `shadow_offer` and `shadow_estimate`
//! (shaders/common/shading.wgsl), in the same f32 arithmetic and the same random numbers.
//!
//! A pixel's loop over lights offers each light's unshadowed radiance `c_i` ([`Draws::offer`]).
//! `K` weighted reservoirs each keep one light, in proportion to `w_i = luminance(c_i)`: one
//! uniform number `u_i` a light, reservoir `k` taking light `i` where
//! `fract(u_i + k / K) < w_i / (w_1 + ... + w_i)`. Each reservoir's draw has the marginal
//! `w_i / W`, and the `K` shifts stratify them. [`Draws::estimate`] then traces the `K` rays and
//! returns the ratio estimator (Heitz et al. 2018, "Combining analytic direct illumination and
//! stochastic shadows"): the unshadowed sum `U` times, per channel, `sum_k s_k V_k / sum_k s_k`,
//! with `s_k = c_k / w_k` and `V_k` 1 where ray `k` is clear.
//!
//! Its bias: the ratio of two estimates is biased for finite `K` and consistent as `K` grows.
//! Where the drawn lights share one colour, `s_k` is that colour for every `k` and the estimate
//! is `U` times the fraction of clear rays, whose expectation is `sum_i w_i V_i / W`: then
//! unbiased where the lights' colours are alike. Exact where every drawn ray is clear (`U`) or
//! every one blocked (no light).

use glam::Vec3;

use crate::motion::pcg;

/// The luminance shading weighs draws by, in f32 (`shading_luminance`).
pub fn shading_luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// One pixel's draws over the lights of one loop.
#[derive(Clone, Debug)]
pub struct Draws {
    rays: u32,
    seed: u32,
    rng: u32,
    total: f32,
    lit: Vec3,
    targets: Vec<Vec3>,
    shares: Vec<Vec3>,
}

impl Draws {
    /// The draws of `rays` rays at `pixel` in frame `frame` (`shadow_frame`), for the loop
    /// numbered `loops` in its invocation (0 but for MSAA's later sample groups).
    pub fn new(rays: u32, pixel: (u32, u32), frame: u32, loops: u32) -> Self {
        Self {
            rays,
            seed: pcg(pixel.0 ^ pcg(pixel.1 ^ pcg(frame ^ pcg(loops)))),
            rng: 0,
            total: 0.0,
            lit: Vec3::ZERO,
            targets: vec![Vec3::ZERO; rays as usize],
            shares: vec![Vec3::ZERO; rays as usize],
        }
    }

    /// Offers a light's unshadowed radiance `c` from position `towards`.
    pub fn offer(&mut self, c: Vec3, towards: Vec3) {
        let w = shading_luminance(c);
        if !(w > 0.0) {
            return;
        }
        if self.total == 0.0 {
            self.rng = self.seed;
        }
        self.total += w;
        self.lit += c;
        self.rng = pcg(self.rng);
        let u = (self.rng >> 8) as f32 * (1.0 / 16_777_216.0);
        let keep = w / self.total;
        let share = c / w;
        for k in 0..self.rays as usize {
            let x = u + k as f32 / self.rays as f32;
            if x - x.floor() < keep {
                self.targets[k] = towards;
                self.shares[k] = share;
            }
        }
    }

    /// The positions of the lights drawn, one a ray (none where nothing was offered).
    pub fn drawn(&self) -> &[Vec3] {
        if self.total == 0.0 { &[] } else { &self.targets }
    }

    /// The loop's sum `c` (its emission plus every offered light's radiance) with the offered
    /// part scaled by the rays' ratio, `blocked` deciding each drawn light's ray; `c` where
    /// nothing was offered.
    pub fn estimate(&self, c: Vec3, mut blocked: impl FnMut(Vec3) -> bool) -> Vec3 {
        if self.total == 0.0 {
            return c;
        }
        let (mut drawn, mut clear, mut seen) = (Vec3::ZERO, Vec3::ZERO, 0u32);
        for (t, s) in self.targets.iter().zip(&self.shares) {
            drawn += *s;
            if !blocked(*t) {
                clear += *s;
                seen += 1;
            }
        }
        let fraction = seen as f32 / self.rays as f32;
        let ratio = Vec3::select(drawn.cmpgt(Vec3::ZERO), clear / drawn, Vec3::splat(fraction));
        c - self.lit * (Vec3::ONE - ratio)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each reservoir draws light i with probability w_i / W over many pixels; the estimator's
    /// mean over pixels of one-coloured lights is the shadowed sum (unbiased there), and every
    /// ray clear gives the unshadowed sum exactly.
    #[test]
    fn reservoirs_draw_in_proportion_and_one_colour_is_unbiased() {
        let weights = [1.0f32, 3.0, 0.5, 0.0, 5.5];
        let blocked = [false, true, false, false, true];
        let total: f32 = weights.iter().sum();
        let rays = 4;
        let mut counts = [[0u32; 5]; 4];
        let n = 40_000u32;
        let mut mean = 0.0f64;
        for px in 0..n {
            let mut d = Draws::new(rays, (px % 200, px / 200), 7, 0);
            let mut sum = Vec3::ZERO;
            for (i, &w) in weights.iter().enumerate() {
                let c = Vec3::splat(w);
                sum += c;
                d.offer(c, Vec3::new(i as f32, 0.0, 0.0));
            }
            for (k, t) in d.drawn().iter().enumerate() {
                counts[k][t.x as usize] += 1;
            }
            let e = d.estimate(sum, |t| blocked[t.x as usize]);
            mean += f64::from(e.x) / f64::from(n);
            let clear = d.estimate(sum, |_| false);
            assert_eq!(clear, sum, "every ray clear: the unshadowed sum");
        }
        for row in &counts {
            for (i, &c) in row.iter().enumerate() {
                let p = f64::from(weights[i] / total);
                let got = f64::from(c) / f64::from(n);
                let sd = (p * (1.0 - p) / f64::from(n)).sqrt();
                assert!((got - p).abs() <= 5.0 * sd + 1e-12, "light {i}: {got} vs {p}");
            }
        }
        let want: f32 = weights
            .iter()
            .zip(&blocked)
            .filter(|(_, b)| !**b)
            .map(|(w, _)| w)
            .sum();
        assert!(
            (mean - f64::from(want)).abs() < 0.02 * f64::from(total),
            "mean {mean} vs the shadowed sum {want}"
        );
    }

    /// Nothing offered: the sum unchanged and no ray drawn; every ray blocked: no light left.
    #[test]
    fn nothing_offered_and_all_blocked() {
        let d = Draws::new(3, (1, 2), 0, 0);
        assert!(d.drawn().is_empty());
        assert_eq!(d.estimate(Vec3::ONE, |_| true), Vec3::ONE);
        let mut d = Draws::new(3, (1, 2), 0, 0);
        let emission = Vec3::new(0.25, 0.0, 0.0);
        let c = Vec3::new(1.0, 2.0, 0.5);
        d.offer(c, Vec3::ZERO);
        let e = d.estimate(emission + c, |_| true);
        assert!((e - emission).abs().max_element() < 1e-6, "{e}");
    }
}
