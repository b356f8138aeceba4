//! The hierarchy's f64 oracle tested: power kept at every level, the fixed-shape build, the
//! blending weights, a single light, the flattened lights, the error over alpha.

use super::*;
use crate::light::falloff_infinite;
use glam::Vec3;

fn rng(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn lights(n: usize, extent: f64, seed: u64) -> Vec<Light> {
    let mut r = rng(seed);
    (0..n)
        .map(|_| {
            let p = Vec3::new(
                (r() * extent) as f32,
                (r() * extent * 0.3) as f32,
                (r() * extent) as f32,
            );
            let c = Vec3::new(0.2 + r() as f32, 0.2 + r() as f32, 0.2 + r() as f32);
            Light::point(p, 1.0, c, (0.5 + 2.0 * r()) as f32)
        })
        .collect()
}

fn params(alpha: f64) -> HierarchyParams {
    HierarchyParams {
        alpha,
        spacing: 0.5,
        finest_nodes: 0.25,
        growth: GROWTH,
        ramp: RAMP,
        top_lights: 16,
        sample_from: None,
        spot_bins: SPOT_BINS,
    }
}

/// The infinite-range sum of the lights' power times the inverse-square falloff.
fn exact(lights: &[Light], x: DVec3) -> DVec3 {
    lights
        .iter()
        .map(|l| power(l) * falloff_infinite(x.distance(l.position.as_dvec3())))
        .sum()
}

fn estimate(h: &Hierarchy, x: DVec3) -> DVec3 {
    h.estimate(x, |l, d| l.power * falloff_infinite(d), |_| DVec3::ZERO)
}

#[test]
fn every_level_holds_the_lights_whole_power() {
    let ls = lights(3000, 60.0, 1);
    let h = Hierarchy::build(&ls, params(2.0));
    assert!(h.levels.len() >= 4, "{} levels", h.levels.len());
    assert!(h.levels.last().unwrap().len() <= 16);
    let total: DVec3 = ls.iter().map(power).sum();
    for (l, p) in h.level_power().iter().enumerate() {
        assert!(
            (*p - total).abs().max_element() < 1e-9 * total.max_element(),
            "level {l}"
        );
    }
    // Coarser grids hold fewer lights (the finest may hold more than the point lights:
    // up to 8 nodes a light where the spacing is small against their spread).
    for w in h.levels[1..].windows(2) {
        assert!(w[1].len() < w[0].len());
    }
}

/// The fixed-shape build (the GPU's oracle) with `build`'s spacing and levels is `build`;
/// with moved lights it keeps the shape and still holds the whole power at every level.
#[test]
fn a_fixed_shape_build_is_the_build_and_keeps_its_shape() {
    let ls = lights(2000, 40.0, 5);
    let h = Hierarchy::build(&ls, params(2.0));
    let f = Hierarchy::build_fixed(&ls, h.params, h.h, h.levels.len());
    assert_eq!(f.levels, h.levels);
    let moved: Vec<Light> = ls
        .iter()
        .map(|l| Light {
            position: l.position + glam::Vec3::new(3.0, -1.0, 0.5),
            ..*l
        })
        .collect();
    let m = Hierarchy::build_fixed(&moved, h.params, h.h, h.levels.len());
    assert_eq!(m.levels.len(), h.levels.len());
    let total: DVec3 = ls.iter().map(power).sum();
    for p in m.level_power() {
        assert!((p - total).abs().max_element() < 1e-9 * total.max_element());
    }
}

/// With the papers' bands, with growing ones (`growth` above 1: a level whole between its
/// ramps) and with narrower ramps (`ramp` below 2).
#[test]
fn the_blending_weights_sum_to_one_at_every_distance() {
    for (growth, ramp) in [
        (1.0, 2.0),
        (1.15, 2.0),
        (1.5, 2.0),
        (1.0, 1.25),
        (1.15, 1.5),
    ] {
        let p = HierarchyParams {
            growth,
            ramp,
            ..params(1.5)
        };
        weights_sum_to_one(&Hierarchy::build(&lights(3000, 60.0, 2), p));
    }
}

fn weights_sum_to_one(h: &Hierarchy) {
    let n = h.levels.len();
    assert!(n >= 3, "{n} levels");
    for k in 0..20_000 {
        let d = k as f64 * 0.01;
        let sum: f64 = (0..n).map(|l| h.band(l, d)).sum();
        assert!((sum - 1.0).abs() < 1e-12, "d {d}: {sum}");
        for l in 0..n {
            let (outer, inner) = h.sphere(l);
            if outer.is_some_and(|o| d >= o) || (l > 0 && d <= inner) {
                assert_eq!(h.band(l, d), 0.0, "level {l} at {d} outside its sphere");
            }
        }
    }
}

#[test]
fn a_single_light_is_exact_at_every_distance() {
    for p in [Vec3::new(0.3, 1.7, -2.2), Vec3::new(100.25, -3.0, 7.5)] {
        let ls = [Light::point(p, 1.0, Vec3::new(1.0, 0.5, 0.25), 3.0)];
        // Every level there may be, with the papers' bands, growing ones and narrow ramps.
        for (growth, ramp) in [(1.0, 2.0), (1.2, 2.0), (1.15, 1.25)] {
            let pr = HierarchyParams {
                growth,
                ramp,
                ..params(1.0)
            };
            let h = Hierarchy::build_fixed(&ls, pr, pr.spacing, MAX_LEVELS);
            assert_eq!(h.levels.len(), MAX_LEVELS);
            for k in 0..400 {
                let d = 0.05 * 1.03f64.powi(k);
                let x = p.as_dvec3() + DVec3::new(0.6, -0.48, 0.64) * d;
                let (e, got) = (exact(&ls, x), estimate(&h, x));
                assert!(
                    (got - e).abs().max_element() <= 1e-9 * e.max_element(),
                    "growth {growth}, ramp {ramp} at {d}: {got} against {e}"
                );
            }
        }
    }
}

/// The flattened lights shade what the estimate sums, band for band, and their bands are
/// the levels'; a scene of one point light and one spot shades as the lights do at
/// infinite range.
#[test]
fn the_flattened_lights_shade_the_estimate() {
    use crate::light::{Range, shade as shade_lights};
    let ls = lights(1500, 30.0, 6);
    let h = Hierarchy::build(&ls, params(2.0));
    let (flat, bands) = h.flatten(1e6);
    assert_eq!(flat.len(), h.levels.iter().map(Vec::len).sum::<usize>());
    let mut k = 0;
    for (level, l) in h.levels.iter().enumerate() {
        for _ in l {
            for d in [0.0, 0.7, 1.3, 2.9, 6.1, 13.0, 40.0] {
                assert_eq!(bands[k].weight(d), h.band(level, d), "level {level} at {d}");
            }
            let (outer, _) = h.sphere(level);
            assert_eq!(outer.unwrap_or(f64::INFINITY), bands[k].outer());
            k += 1;
        }
    }
    let material = Material::new(Vec3::new(0.7, 0.6, 0.5), 0.3);
    let mut r = rng(7);
    for _ in 0..50 {
        let p = DVec3::new(r() * 30.0, 0.0, r() * 30.0);
        let (n, v) = (DVec3::Y, DVec3::new(0.0, 0.8, 0.6));
        let lambert = shade(p, n, v, &material, &flat, &bands);
        let sum = h.estimate(
            p,
            |l, d| {
                let to = (l.position - p) / d;
                l.power
                    * falloff_infinite(d)
                    * crate::brdf::brdf_cos(
                        &material.brdf,
                        material.base_color.as_dvec3(),
                        n,
                        to,
                        v,
                    )
            },
            |_| DVec3::ZERO,
        ) + material.emissive.as_dvec3();
        // The flattened lights are the scene model's, in f32.
        assert!(
            (lambert - sum).abs().max_element() <= 1e-5 * sum.max_element(),
            "{lambert} against {sum}"
        );
    }
    let mut two = vec![Light::point(Vec3::new(1.0, 2.0, 3.0), 1.0, Vec3::ONE, 2.0)];
    two.push(Light {
        kind: LightKind::Spot {
            direction: Vec3::NEG_Y,
            inner_angle: 0.3,
            outer_angle: 0.6,
        },
        ..Light::point(Vec3::new(4.0, 3.0, 1.0), 1.0, Vec3::ONE, 5.0)
    });
    let h = Hierarchy::build(
        &two,
        HierarchyParams {
            top_lights: 0,
            sample_from: None,
            ..params(1.0)
        },
    );
    let (flat, bands) = h.flatten(1e6);
    for x in [0.5, 3.0, 9.0, 27.0, 81.0] {
        let p = DVec3::new(x, 0.0, 2.0);
        let (n, v) = (DVec3::Y, DVec3::Y);
        let want = shade_lights(p, n, v, &material, &two, Range::Infinite);
        let got = shade(p, n, v, &material, &flat, &bands);
        assert!(
            (got - want).abs().max_element() <= 1e-9 * want.max_element(),
            "{x}"
        );
    }
}

/// 300 points drawn with `seed` in the 40 m box of [`lights`]' scenes.
fn points(seed: u64) -> Vec<DVec3> {
    let mut r = rng(seed);
    (0..300)
        .map(|_| DVec3::new(r() * 40.0, r() * 12.0, r() * 40.0))
        .collect()
}

/// The mean relative error of `h`'s estimate at `xs` against `ls` at infinite range.
fn mean_error(h: &Hierarchy, ls: &[Light], xs: &[DVec3]) -> f64 {
    xs.iter()
        .map(|&x| {
            let (e, got) = (exact(ls, x), estimate(h, x));
            ((got - e).abs() / e).element_sum() / 3.0
        })
        .sum::<f64>()
        / xs.len() as f64
}

#[test]
fn the_error_falls_as_alpha_grows() {
    let ls = lights(2000, 40.0, 4);
    let xs = points(5);
    let error = |alpha: f64| mean_error(&Hierarchy::build(&ls, params(alpha)), &ls, &xs);
    // Below the papers' 1 as well.
    let errors: Vec<f64> = [0.5, 0.75, 1.0, 2.0, 4.0, 8.0, 16.0].map(error).to_vec();
    for w in errors.windows(2) {
        assert!(w[1] < w[0], "{errors:?}");
    }
    assert!(errors[6] < 1e-4 && errors[2] > 1e-3, "{errors:?}");
}

/// Growing bands take the coarse levels from farther: at the same alpha the error falls as
/// `growth` grows from 1 to 1.25 (in this small box it rises again by 1.5, where the last
/// level's few aggregates take over), and it falls as alpha grows at a growth above 1.
#[test]
fn the_error_falls_as_the_bands_grow() {
    let ls = lights(2000, 40.0, 4);
    let xs = points(6);
    let error = |alpha: f64, growth: f64| {
        let p = HierarchyParams {
            growth,
            ..params(alpha)
        };
        let h = Hierarchy::build(&ls, p);
        assert!(h.levels.len() >= 3);
        mean_error(&h, &ls, &xs)
    };
    let by_growth: Vec<f64> = [1.0, 1.1, 1.25].map(|g| error(1.0, g)).to_vec();
    for w in by_growth.windows(2) {
        assert!(w[1] < w[0], "{by_growth:?}");
    }
    let by_alpha: Vec<f64> = [0.5, 1.0, 2.0, 4.0].map(|a| error(a, 1.15)).to_vec();
    for w in by_alpha.windows(2) {
        assert!(w[1] < w[0], "{by_alpha:?}");
    }
}

/// `lights(n, ..)` with every `k`-th light a spot of `outer_deg`, aimed mostly down (tilted up
/// to 60 degrees), as the light generator aims them.
fn with_spots(ls: &[Light], k: usize, outer_deg: f32, seed: u64) -> Vec<Light> {
    let mut r = rng(seed);
    ls.iter()
        .enumerate()
        .map(|(i, l)| {
            let (tilt, az) = (r() * 60f64.to_radians(), r() * std::f64::consts::TAU);
            if i % k != 0 {
                return *l;
            }
            let direction = DVec3::new(tilt.sin() * az.cos(), -tilt.cos(), tilt.sin() * az.sin());
            Light {
                kind: LightKind::Spot {
                    direction: direction.as_vec3(),
                    inner_angle: 0.8 * outer_deg.to_radians(),
                    outer_angle: outer_deg.to_radians(),
                },
                ..*l
            }
        })
        .collect()
}

/// The infinite-range sum of the lights' power times the inverse-square falloff and cone.
fn exact_cones(lights: &[Light], x: DVec3) -> DVec3 {
    lights
        .iter()
        .map(|l| {
            let to = l.position.as_dvec3() - x;
            power(l) * falloff_infinite(to.length()) * l.cone_toward(to.normalize())
        })
        .sum()
}

fn estimate_cones(h: &Hierarchy, x: DVec3) -> DVec3 {
    h.estimate(
        x,
        |l, d| l.power * falloff_infinite(d),
        |s| {
            let to = s.position.as_dvec3() - x;
            power(s) * falloff_infinite(to.length()) * s.cone_toward(to.normalize())
        },
    )
}

/// Every level holds the lights' whole flux (a light's power times its cone's, a point's
/// the whole sphere's), spots in their bins' aggregates included; the levels keep their
/// spots' aggregates apart by bin.
#[test]
fn every_level_holds_the_spots_whole_flux() {
    let ls = with_spots(&lights(3000, 60.0, 1), 3, 35.0, 2);
    let flux = |l: &Light| match l.cone() {
        None => spots::POINT_FLUX,
        Some((_, ci, co)) => spots::spot_flux(ci.into(), co.into()),
    };
    let total: DVec3 = ls.iter().map(|l| power(l) * flux(l)).sum();
    // No bins (the default: the spots in the point lights' nodes) and 5 a side.
    for spot_bins in [0, 5] {
        let p = HierarchyParams {
            spot_bins,
            ..params(2.0)
        };
        let h = Hierarchy::build(&ls, p);
        assert!(h.levels.len() >= 4, "{} levels", h.levels.len());
        assert_eq!(h.bins.is_empty(), spot_bins == 0, "{} bins", h.bins.len());
        assert!(spot_bins == 0 || h.bins.len() >= 4, "{} bins", h.bins.len());
        for (k, level) in h.levels.iter().enumerate().skip(1) {
            let sum: DVec3 = level
                .iter()
                .map(|l| match l.bin {
                    0 => l.power * spots::POINT_FLUX,
                    b => l.power * h.bins[b as usize - 1].flux(),
                })
                .sum();
            assert!(
                (sum - total).abs().max_element() < 1e-6 * total.max_element(),
                "{spot_bins} bins, level {k}: {sum} against {total}"
            );
            assert_eq!(level.iter().any(|l| l.bin > 0), spot_bins > 0);
            assert!(level.windows(2).all(|w| w[0].bin <= w[1].bin));
        }
        let f = Hierarchy::build_fixed(&ls, h.params, h.h, h.levels.len());
        assert_eq!((f.levels, f.bins), (h.levels, h.bins));
    }
    // Without bins the levels are the point lights' grids: as many aggregates as the same
    // lights make as point lights.
    let as_points: Vec<Light> = ls
        .iter()
        .map(|l| Light {
            kind: LightKind::Point,
            ..*l
        })
        .collect();
    let (a, b) = (
        Hierarchy::build(&ls, params(2.0)),
        Hierarchy::build(&as_points, params(2.0)),
    );
    let sizes = |h: &Hierarchy| h.levels[1..].iter().map(Vec::len).collect::<Vec<_>>();
    assert_eq!(sizes(&a), sizes(&b));
}

/// A lone spot in a bin of its own is exact at every distance, inside its cone and at its edge
/// and outside it.
#[test]
fn a_single_spot_is_exact_at_every_distance() {
    let spot = Light {
        kind: LightKind::Spot {
            direction: Vec3::new(0.3, -1.0, 0.2).normalize(),
            inner_angle: 0.4,
            outer_angle: 0.7,
        },
        ..Light::point(
            Vec3::new(0.3, 1.7, -2.2),
            1.0,
            Vec3::new(1.0, 0.5, 0.25),
            3.0,
        )
    };
    let ls = [spot];
    let pr = HierarchyParams {
        spot_bins: 5,
        ..params(1.0)
    };
    let h = Hierarchy::build_fixed(&ls, pr, pr.spacing, MAX_LEVELS);
    let axis = spot.cone().unwrap().0.as_dvec3();
    let side = axis.cross(DVec3::X).normalize();
    let mut lit = 0;
    for angle in [0.0, 0.3, 0.55, 0.69, 1.0] {
        let dir = axis * f64::cos(angle) + side * f64::sin(angle);
        for k in 0..400 {
            let d = 0.05 * 1.03f64.powi(k);
            let x = spot.position.as_dvec3() + dir * d;
            let (e, got) = (exact_cones(&ls, x), estimate_cones(&h, x));
            lit += usize::from(e.x > 0.0);
            assert!(
                (got - e).abs().max_element() <= 1e-6 * e.max_element() + 1e-12,
                "angle {angle} at {d}: {got} against {e}"
            );
        }
    }
    assert!(lit >= 1600, "{lit}");
}

/// Spots aimed mostly down, gathered in a 2 m box and seen from 20 to 40 m away (where
/// coarse levels light them) in every direction: the estimate's error falls as the bins narrow
/// the aggregates' cones (one bin for all is nearly a point light's lobe).
#[test]
fn far_spots_are_lit_closer_with_narrower_bins() {
    let ls = with_spots(&lights(400, 2.0, 4), 1, 35.0, 3);
    let mut r = rng(9);
    let xs: Vec<DVec3> = (0..400)
        .map(|_| {
            let d = DVec3::new(r() - 0.5, r() - 0.5, r() - 0.5).normalize() * (20.0 + 20.0 * r());
            DVec3::splat(1.0) + d
        })
        .collect();
    let error = |spot_bins: u32| {
        let p = HierarchyParams {
            spot_bins,
            ..params(1.0)
        };
        let h = Hierarchy::build(&ls, p);
        let (mut diff, mut sum) = (0.0, 0.0);
        for &x in &xs {
            let (e, got) = (exact_cones(&ls, x), estimate_cones(&h, x));
            diff += (got - e).abs().element_sum();
            sum += e.element_sum();
        }
        diff / sum
    };
    let by_bins: Vec<f64> = [1, 3, 5, 9].map(error).to_vec();
    eprintln!("{by_bins:?}");
    for w in by_bins.windows(2) {
        assert!(w[1] < w[0], "{by_bins:?}");
    }
}
