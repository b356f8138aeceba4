//! A flattened light's band (its weight at every distance), and stochastic band selection:
//! the band drawn each frame as a hard one whose expectation is the soft band's weight, each
//! light's draw from the frame's seed and its draw id.

/// A flattened light's band: its weight at distance `d` is
/// `min(rising, falling)`, rising from 0 at `inner` to 1 at `ramp inner` (1 throughout where
/// `inner` is 0: level 0) and falling from 1 at `r` to 0 at `ramp r` (1 throughout where `r` is
/// infinite: the last level, and the spots); the papers' ramps are 2
/// ([`super::RAMP`]), and a level's `inner` is the `r` of the level below, so the two weights
/// sum to 1 over that ramp. A sampled band (`hard`, [`Band::sampled`]) is 1 for `inner < d < r`
/// and 0 elsewhere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Band {
    /// Where the weight starts to rise (0: it is 1 from the light out).
    pub inner: f64,
    /// Where it is 1; it falls to 0 at `ramp` times this (infinite: it never falls). A hard
    /// band's end.
    pub r: f64,
    /// A sampled band: weight 1 between `inner` and `r`.
    pub hard: bool,
    /// How far each ramp runs: from `inner` to `ramp inner` and from `r` to `ramp r`, in
    /// (1, 2] ([`super::HierarchyParams::ramp`]).
    pub ramp: f64,
}

/// The draw in (0, 1) of the light of draw id `id` in the frame of `seed`: PCG's hash of the id
/// mixed with the seed's, its top bits (`shaders/lights/hierarchy.wgsl`'s `band_xi`). A point
/// light's id is its index among the shaded lights, an aggregate's [`node_draw`] of its node:
/// so a frame's draws are the same in every build of it.
pub fn band_xi(seed: u32, id: u32) -> f64 {
    let h = crate::motion::pcg(id ^ crate::motion::pcg(seed));
    f64::from(crate::stochastic::unit(h))
}

/// The draw id of the aggregate of level `level` at the node of key `key` (1 plus the node's
/// index in its level's box of nodes, as the GPU build's hash table keys it).
pub fn node_draw(level: u32, key: u32) -> u32 {
    crate::motion::pcg(key ^ crate::motion::pcg(level))
}

impl Band {
    /// A soft band (`hard` false) from `inner` and `r`, with the papers' ramps (2).
    pub fn new(inner: f64, r: f64) -> Self {
        Self::with_ramp(inner, r, super::RAMP)
    }

    /// A soft band from `inner` and `r` whose ramps run to `ramp` times them.
    pub fn with_ramp(inner: f64, r: f64, ramp: f64) -> Self {
        Self {
            inner,
            r,
            hard: false,
            ramp,
        }
    }

    /// The band drawn with `xi` in (0, 1): weight 1 for
    /// `inner (1 + (ramp - 1) xi) < d < r (ramp - (ramp - 1) xi)`, 0 elsewhere (from 0 where
    /// `inner` is 0; unbounded where `r` is infinite). The same `xi` cuts both edges, so the
    /// probability over `xi` that it holds `d` is `min(rising, falling)`, the soft band's
    /// weight: unbiased. A hard band stays as it is.
    pub fn sampled(&self, xi: f64) -> Self {
        if self.hard {
            return *self;
        }
        let t = (self.ramp - 1.0) * xi;
        Self {
            inner: self.inner * (1.0 + t),
            r: if self.r.is_infinite() {
                f64::INFINITY
            } else {
                self.r * (self.ramp - t)
            },
            hard: true,
            ramp: self.ramp,
        }
    }

    /// The weight at distance `d`.
    pub fn weight(&self, d: f64) -> f64 {
        if self.hard {
            return if d > self.inner && d < self.r {
                1.0
            } else {
                0.0
            };
        }
        // As `light_band` (shaders/common/shading.wgsl) has it: over `ramp - 1`, which is 1
        // for the papers' ramps.
        let slope = 1.0 / (self.ramp - 1.0);
        let rising = if self.inner == 0.0 {
            1.0
        } else if d <= self.inner {
            return 0.0;
        } else {
            ((d - self.inner) / self.inner * slope).min(1.0)
        };
        rising.min(((self.ramp - d / self.r) * slope).clamp(0.0, 1.0))
    }

    /// What the band reaches: `ramp r` (infinite for the last level and the spots; a hard
    /// band's `r`).
    pub fn outer(&self) -> f64 {
        if self.hard {
            self.r
        } else {
            self.ramp * self.r
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sampled band holds `d` with the soft band's weight as its probability over the draw
    /// (the mean over a fine lattice of draws), for level 0's, a middle level's and the last
    /// level's bands; its reach is at most the soft band's; the draws spread over (0, 1).
    #[test]
    fn sampled_bands_are_unbiased() {
        let n = 20_000;
        for band in [
            Band::new(0.0, 2.0),
            Band::new(1.0, 2.0),
            Band::new(4.0, f64::INFINITY),
            Band::with_ramp(1.0, 2.5, 1.25),
            Band::with_ramp(0.0, 2.0, 1.5),
        ] {
            for i in 0..200 {
                let d = f64::from(i) * 0.05 + 0.013;
                let mean = (0..n)
                    .map(|k| band.sampled((f64::from(k) + 0.5) / f64::from(n)).weight(d))
                    .sum::<f64>()
                    / f64::from(n);
                assert!(
                    (mean - band.weight(d)).abs() < 1e-3,
                    "{band:?} at {d}: mean {mean}, weight {}",
                    band.weight(d)
                );
                let s = band.sampled(0.3);
                assert!(s.hard && s.outer() <= band.outer());
                assert_eq!(s.sampled(0.9), s);
            }
        }
        let xis: Vec<f64> = (0..4096).map(|i| band_xi(7, i)).collect();
        assert!(xis.iter().all(|&x| x > 0.0 && x < 1.0));
        let mean = xis.iter().sum::<f64>() / xis.len() as f64;
        assert!((mean - 0.5).abs() < 0.02, "{mean}");
        assert_ne!(band_xi(7, 3), band_xi(8, 3));
    }
}
