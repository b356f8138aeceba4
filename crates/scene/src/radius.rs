//! How a generated light's range is chosen ([`RadiusRule`]): a fixed radius, a cut-off
//! threshold, stochastic light culling's ranges drawn each frame, or the lighting grid
//! hierarchy's bands; its serialised form and its validation.

use serde::{Deserialize, Serialize};

use crate::SceneError;
use crate::stochastic::{StochasticBound, StochasticDraw};

/// How each light's radius is set.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum RadiusRule {
    /// The same radius for every light, metres, > 0.
    Fixed(f32),
    /// The distance at which the un-windowed inverse-square irradiance of the light's brightest
    /// channel falls to this threshold: `r = sqrt(intensity * max(colour) / threshold)`, > 0.
    Threshold(f32),
    /// Stochastic light culling ([`crate::stochastic`]): every frame each light gets a random
    /// range, drawn so that the image is an unbiased estimate of the infinite-range one. The
    /// generated radius is the shortest range (`xi = 1`); `lights.stochastic` draws each
    /// frame's.
    Stochastic {
        /// Bound on one light's standard deviation, > 0: of its exposed incident contribution
        /// (`exposure * intensity * max(colour) * falloff`) with the default `bound: Light`,
        /// of its reflected radiance off the scene's most reflective diffuse-equivalent
        /// surface with `bound: Albedo` ([`crate::stochastic`]).
        error: f32,
        /// What `error` bounds: `Light` (the default, left out of the serialised form) or
        /// `Albedo`.
        #[serde(default, skip_serializing_if = "is_light_bound")]
        bound: StochasticBound,
        /// The exposure `error` is measured at, > 0 (default 1).
        #[serde(default = "unit")]
        exposure: f32,
        /// Frames averaged into one image with fresh ranges, as a renderer accumulates
        /// temporally: 0 (the default) none, otherwise at least 2.
        #[serde(default)]
        accumulate: u32,
        /// Independent draws measured for the noise and bias columns, >= 1 (default 4).
        #[serde(default = "four")]
        seeds: u32,
        /// Interleaved sampling over `n x n` pixel classes, each drawing its own ranges
        /// ([`crate::stochastic`]): 1 (the default, left out of the serialised form so that
        /// earlier cells keep their identifiers) none, up to
        /// [`crate::stochastic::INTERLEAVE_MAX`].
        #[serde(default = "one", skip_serializing_if = "is_one")]
        interleave: u32,
        /// How a frame's numbers are drawn across the lights: `Stratified` (the default, left
        /// out of the serialised form) or `Independent` ([`crate::stochastic`]).
        #[serde(default, skip_serializing_if = "is_stratified")]
        draw: StochasticDraw,
    },
    /// The lighting grid hierarchy ([`crate::hierarchy`]): the point lights near a shading
    /// point as they are, far ones from aggregates on nested grids, every light a sphere of
    /// bounded range; deterministic, with a bias that shrinks as `alpha` grows. The generated
    /// radius is level 0's reach, `2 alpha spacing`.
    Hierarchy {
        /// The accuracy parameter, > 0 (the papers use 1 and more): level `l`'s lights reach
        /// `2 alpha h 2^l`, `h` the finest grid's spacing.
        alpha: f32,
        /// The finest grid's spacing, metres, > 0, at least: it doubles while that grid would
        /// hold more than `finest_nodes` times as many nodes as there are point lights.
        spacing: f32,
        /// The most nodes the finest grid may hold a point light, > 0
        /// (`HierarchyParams::finest_nodes`): 2 by default (left out of the serialised form),
        /// the authors' implementation 0.25.
        #[serde(default = "finest_nodes", skip_serializing_if = "is_finest_nodes")]
        finest_nodes: f32,
        /// How much farther in its grid's units each level's band ends than the level
        /// below's, >= 1 (`HierarchyParams::growth`): 1 by default, the papers' bands (left out
        /// of the serialised form).
        #[serde(default = "growth", skip_serializing_if = "is_growth")]
        growth: f32,
        /// How far each level hands over to the next, from `r_l` to `ramp r_l`, in (1, 2]
        /// (`HierarchyParams::ramp`): 2 by default, the papers' (left out of the serialised
        /// form).
        #[serde(default = "ramp", skip_serializing_if = "is_ramp")]
        ramp: f32,
        /// Stochastic band selection from this level on (`HierarchyParams::sample_from`):
        /// those levels' lights draw their bands each frame, unbiased, with shorter lists.
        /// Absent: none.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        sample_from: Option<u32>,
        /// The spots' direction bins (`HierarchyParams::spot_bins`): 0, none, by default (left
        /// out of the serialised form): the spots spread into the point lights' nodes; 1 to
        /// 16: cells along each side of an octahedral map of their axes.
        #[serde(default = "spot_bins", skip_serializing_if = "is_spot_bins")]
        spot_bins: u32,
    },
}

fn spot_bins() -> u32 {
    crate::hierarchy::SPOT_BINS
}

fn is_spot_bins(n: &u32) -> bool {
    *n == spot_bins()
}

fn is_stratified(d: &StochasticDraw) -> bool {
    *d == StochasticDraw::Stratified
}

fn is_light_bound(b: &StochasticBound) -> bool {
    *b == StochasticBound::Light
}

fn one() -> u32 {
    1
}

fn finest_nodes() -> f32 {
    crate::hierarchy::FINEST_NODES as f32
}

fn is_finest_nodes(r: &f32) -> bool {
    *r == finest_nodes()
}

fn growth() -> f32 {
    crate::hierarchy::GROWTH as f32
}

fn is_growth(g: &f32) -> bool {
    *g == growth()
}

fn ramp() -> f32 {
    crate::hierarchy::RAMP as f32
}

fn is_ramp(c: &f32) -> bool {
    *c == ramp()
}

fn is_one(n: &u32) -> bool {
    *n == 1
}

fn unit() -> f32 {
    1.0
}

fn four() -> u32 {
    4
}

impl RadiusRule {
    /// The hierarchy's parameters where the rule is `Hierarchy` (the last level of at most
    /// [`crate::hierarchy::TOP_LIGHTS`] lights), else `None`.
    pub fn hierarchy_params(&self) -> Option<crate::hierarchy::HierarchyParams> {
        let Self::Hierarchy {
            alpha,
            spacing,
            finest_nodes,
            growth,
            ramp,
            sample_from,
            spot_bins,
        } = *self
        else {
            return None;
        };
        Some(crate::hierarchy::HierarchyParams {
            alpha: alpha.into(),
            spacing: spacing.into(),
            finest_nodes: finest_nodes.into(),
            growth: growth.into(),
            ramp: ramp.into(),
            top_lights: crate::hierarchy::TOP_LIGHTS,
            sample_from: sample_from.map(|l| l as usize),
            spot_bins,
        })
    }

    /// The name of the rule in cell names and result columns: `fixed`, `threshold`,
    /// `stochastic` or `hierarchy`.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Fixed(_) => "fixed",
            Self::Threshold(_) => "threshold",
            Self::Stochastic { .. } => "stochastic",
            Self::Hierarchy { .. } => "hierarchy",
        }
    }

    /// Checks the rule's values; the error names the field (`lights.radius...`), the value
    /// and what is accepted.
    pub fn validate(&self) -> Result<(), SceneError> {
        match *self {
            RadiusRule::Fixed(r) if !(r.is_finite() && r > 0.0) => {
                return Err(SceneError::invalid(
                    "lights.radius",
                    r,
                    "a finite radius > 0",
                ));
            }
            RadiusRule::Threshold(t) if !(t.is_finite() && t > 0.0) => {
                return Err(SceneError::invalid(
                    "lights.threshold",
                    t,
                    "a finite cut-off threshold > 0",
                ));
            }
            RadiusRule::Hierarchy {
                alpha,
                spacing,
                finest_nodes,
                growth,
                ramp,
                spot_bins,
                ..
            } => {
                if spot_bins > 16 {
                    return Err(SceneError::invalid(
                        "lights.radius.spot_bins",
                        spot_bins,
                        "0 (no direction bins, the default) to 16 cells along each side of \
                         the octahedral map of spot axes",
                    ));
                }
                if !(growth.is_finite() && (1.0..=4.0).contains(&growth)) {
                    return Err(SceneError::invalid(
                        "lights.radius.growth",
                        growth,
                        "a finite growth of the bands from 1 (the papers', the default) to 4",
                    ));
                }
                if !(ramp.is_finite() && ramp > 1.0 && ramp <= 2.0) {
                    return Err(SceneError::invalid(
                        "lights.radius.ramp",
                        ramp,
                        "a finite ramp above 1 and at most 2 (the papers', the default)",
                    ));
                }
                if !(finest_nodes.is_finite() && finest_nodes > 0.0) {
                    return Err(SceneError::invalid(
                        "lights.radius.finest_nodes",
                        finest_nodes,
                        "a finite number of nodes a point light > 0 (2 by default; 0.25 the \
                         authors')",
                    ));
                }
                if !(alpha.is_finite() && alpha > 0.0) {
                    return Err(SceneError::invalid(
                        "lights.radius.alpha",
                        alpha,
                        "a finite accuracy parameter > 0",
                    ));
                }
                if !(spacing.is_finite() && spacing > 0.0) {
                    return Err(SceneError::invalid(
                        "lights.radius.spacing",
                        spacing,
                        "a finite grid spacing > 0 (metres)",
                    ));
                }
            }
            RadiusRule::Stochastic {
                error,
                exposure,
                accumulate,
                seeds,
                interleave,
                ..
            } => {
                if !(1..=crate::stochastic::INTERLEAVE_MAX).contains(&interleave) {
                    return Err(SceneError::invalid(
                        "lights.radius.interleave",
                        interleave,
                        format!(
                            "1 (none) to {} (n x n pixel classes)",
                            crate::stochastic::INTERLEAVE_MAX
                        ),
                    ));
                }
                if !(error.is_finite() && error > 0.0) {
                    return Err(SceneError::invalid(
                        "lights.radius.error",
                        error,
                        "a finite error bound > 0",
                    ));
                }
                if !(exposure.is_finite() && exposure > 0.0) {
                    return Err(SceneError::invalid(
                        "lights.radius.exposure",
                        exposure,
                        "a finite exposure > 0",
                    ));
                }
                if accumulate == 1 {
                    return Err(SceneError::invalid(
                        "lights.radius.accumulate",
                        accumulate,
                        "0 (no accumulation) or at least 2 frames",
                    ));
                }
                if seeds == 0 {
                    return Err(SceneError::invalid(
                        "lights.radius.seeds",
                        seeds,
                        "at least 1 seed",
                    ));
                }
            }
            _ => {}
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::LightSpec;

    #[test]
    fn bad_stochastic_settings_name_their_field() {
        let rule = |error: f32, accumulate: u32, seeds: u32| LightSpec {
            radius: RadiusRule::Stochastic {
                error,
                bound: StochasticBound::Light,
                exposure: 1.0,
                accumulate,
                seeds,
                interleave: 1,
                draw: StochasticDraw::Stratified,
            },
            ..LightSpec::default()
        };
        let interleaved = |interleave: u32| LightSpec {
            radius: RadiusRule::Stochastic {
                error: 0.1,
                bound: StochasticBound::Light,
                exposure: 1.0,
                accumulate: 0,
                seeds: 4,
                interleave,
                draw: StochasticDraw::Stratified,
            },
            ..LightSpec::default()
        };
        for (spec, field) in [
            (rule(0.0, 0, 4), "lights.radius.error = 0"),
            (rule(-1.0, 0, 4), "lights.radius.error = -1"),
            (rule(f32::NAN, 0, 4), "lights.radius.error = NaN"),
            (rule(f32::INFINITY, 0, 4), "lights.radius.error = inf"),
            (rule(0.1, 1, 4), "lights.radius.accumulate = 1"),
            (rule(0.1, 0, 0), "lights.radius.seeds = 0"),
            (interleaved(0), "lights.radius.interleave = 0"),
            (interleaved(9), "lights.radius.interleave = 9"),
        ] {
            let e = spec.validate().unwrap_err().to_string();
            assert!(e.contains(field), "{e}");
        }
        assert!(rule(0.1, 4, 1).validate().is_ok());
        assert!(rule(0.1, 0, 4).validate().is_ok());
        assert!(interleaved(8).validate().is_ok());
        // Interleave 1 is left out of the serialised form (cell identifiers stay), and read
        // back as the default.
        let text = ron::to_string(&rule(0.1, 0, 4).radius).unwrap();
        assert!(!text.contains("interleave"), "{text}");
        let back: RadiusRule = ron::from_str("Stochastic(error: 0.1)").unwrap();
        assert_eq!(back, rule(0.1, 0, 4).radius);
        let text = ron::to_string(&interleaved(2).radius).unwrap();
        assert!(text.contains("interleave:2"), "{text}");
        // The bound likewise: `Light` left out, `Albedo` named.
        assert!(!text.contains("bound"), "{text}");
        let back: RadiusRule = ron::from_str("Stochastic(error: 0.1, bound: Albedo)").unwrap();
        assert!(matches!(
            back,
            RadiusRule::Stochastic {
                bound: StochasticBound::Albedo,
                ..
            }
        ));
        assert!(ron::to_string(&back).unwrap().contains("bound:Albedo"));
        let e = ron::from_str::<RadiusRule>("Stochastic(error: 0.1, bound: Peak)").unwrap_err();
        assert!(e.to_string().contains("Light"), "{e}");
        // The draw likewise: `Stratified` left out, `Independent` named.
        assert!(!text.contains("draw"), "{text}");
        let back: RadiusRule = ron::from_str("Stochastic(error: 0.1, draw: Independent)").unwrap();
        assert!(matches!(
            back,
            RadiusRule::Stochastic {
                draw: StochasticDraw::Independent,
                ..
            }
        ));
        assert!(ron::to_string(&back).unwrap().contains("draw:Independent"));
        let e = ron::from_str::<RadiusRule>("Stochastic(error: 0.1, draw: Sobol)").unwrap_err();
        assert!(e.to_string().contains("Stratified"), "{e}");
    }

    /// The hierarchy's alpha is any finite value above 0 (below the papers' 1 too), its
    /// spacing any finite one above 0; bad ones name their field.
    #[test]
    fn bad_hierarchy_settings_name_their_field() {
        let spec =
            |alpha: f32, spacing: f32, finest_nodes: f32, growth: f32, ramp: f32| LightSpec {
                radius: RadiusRule::Hierarchy {
                    alpha,
                    spacing,
                    finest_nodes,
                    growth,
                    ramp,
                    sample_from: None,
                    spot_bins: crate::hierarchy::SPOT_BINS,
                },
                ..LightSpec::default()
            };
        let rule = |alpha: f32, spacing: f32| spec(alpha, spacing, 2.0, 1.0, 2.0);
        let nodes = |finest_nodes: f32| spec(1.0, 0.25, finest_nodes, 1.0, 2.0);
        let growth = |growth: f32| spec(1.0, 0.25, 2.0, growth, 2.0);
        let ramp = |ramp: f32| spec(1.0, 0.25, 2.0, 1.0, ramp);
        for (spec, field) in [
            (ramp(1.0), "lights.radius.ramp = 1"),
            (ramp(2.5), "lights.radius.ramp = 2.5"),
            (ramp(f32::INFINITY), "lights.radius.ramp = inf"),
        ] {
            let e = spec.validate().unwrap_err().to_string();
            assert!(e.contains(field) && e.contains("above 1"), "{e}");
        }
        assert!(ramp(1.25).validate().is_ok());
        for (spec, field) in [
            (growth(0.9), "lights.radius.growth = 0.9"),
            (growth(4.5), "lights.radius.growth = 4.5"),
            (growth(f32::NAN), "lights.radius.growth = NaN"),
        ] {
            let e = spec.validate().unwrap_err().to_string();
            assert!(e.contains(field) && e.contains("from 1"), "{e}");
        }
        assert!(growth(1.15).validate().is_ok());
        for (spec, field) in [
            (nodes(0.0), "lights.radius.finest_nodes = 0"),
            (nodes(f32::NAN), "lights.radius.finest_nodes = NaN"),
            (rule(0.0, 0.25), "lights.radius.alpha = 0"),
            (rule(-1.0, 0.25), "lights.radius.alpha = -1"),
            (rule(f32::NAN, 0.25), "lights.radius.alpha = NaN"),
            (rule(f32::INFINITY, 0.25), "lights.radius.alpha = inf"),
            (rule(1.0, 0.0), "lights.radius.spacing = 0"),
        ] {
            let e = spec.validate().unwrap_err().to_string();
            assert!(e.contains(field) && e.contains("> 0"), "{e}");
        }
        for alpha in [0.5, 0.8, 1.0, 4.0] {
            assert!(rule(alpha, 0.25).validate().is_ok(), "{alpha}");
        }
        assert!(nodes(0.25).validate().is_ok());
        // The default is left out of the serialised form (cell identifiers stay), and read
        // back; another value is named.
        let text = ron::to_string(&rule(1.0, 0.25).radius).unwrap();
        assert!(!text.contains("finest_nodes"), "{text}");
        let back: RadiusRule = ron::from_str("Hierarchy(alpha: 1.0, spacing: 0.25)").unwrap();
        assert_eq!(back, rule(1.0, 0.25).radius);
        let text = ron::to_string(&nodes(0.25).radius).unwrap();
        assert!(text.contains("finest_nodes:0.25"), "{text}");
        assert!(!text.contains("growth"), "{text}");
        let text = ron::to_string(&growth(1.15).radius).unwrap();
        assert!(text.contains("growth:1.15"), "{text}");
        let back: RadiusRule =
            ron::from_str("Hierarchy(alpha: 1.0, spacing: 0.25, growth: 1.15)").unwrap();
        assert_eq!(back, growth(1.15).radius);
    }
}
