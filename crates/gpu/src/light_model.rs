//! The light model: how a scene's lights are shaded, fixed when the scene is uploaded
//! ([`crate::GpuScene::upload_with`]). Where the lights' ranges come from (their own radii, ranges
//! drawn each frame, the lighting grid hierarchy's bands) decides what the passes that write the
//! lights may write and what shading reads; with the lights' kinds it makes the [`LightPath`],
//! the one value the frame's flags and every shading pipeline's constants are made from.
//!
//! Nothing changes a scene's model after its upload: a pass that writes the lights
//! ([`crate::stochastic::StochasticRanges`], [`crate::hierarchy::GpuHierarchy`]) checks that the
//! scene was uploaded for what it writes, and a renderer built for one path refuses a scene of
//! another.

use manylights_scene::RadiusRule;

use crate::layout::{
    FRAME_FLAG_BAND_POINTS, FRAME_FLAG_POINT_LIGHTS, FRAME_FLAG_STOCHASTIC_POINTS,
};

/// Where the lights' ranges come from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Ranges {
    /// Each light's own radius as uploaded (a fixed radius or a cut-off threshold), shaded with
    /// the windowed falloff.
    CutOff,
    /// Stochastic light culling: the lights from `first` on draw a range and alpha each frame
    /// on the GPU (`lights.stochastic`), over `interleave` x `interleave` pixel classes (1:
    /// one range a light).
    Stochastic {
        /// The first drawn light (the lights before it keep their own radii).
        first: u32,
        /// Pixel classes a side (1: no interleaving).
        interleave: u32,
    },
    /// The lighting grid hierarchy: every light carries its band (`GpuLight::with_band`),
    /// written by its build on the GPU, and the bands hand over from one level to the next over
    /// `ramp` (the frame's `band_ramp`).
    Hierarchy {
        /// The bands' ramp (above 1 and at most 2).
        ramp: f32,
    },
}

/// How a scene's lights are shaded: their ranges, and whether the short path of point lights
/// may be taken where every light allows it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightModel {
    /// Where the lights' ranges come from.
    pub ranges: Ranges,
    /// Shade every light with the general model (each light's cone and alpha read) even where
    /// the lights would allow the short path of point lights: the short path's oracle.
    pub general: bool,
}

/// The band ramp of the papers, which the frame carries where no hierarchy sets its own.
pub const DEFAULT_BAND_RAMP: f32 = 2.0;

impl LightModel {
    /// Each light's own radius, the windowed falloff.
    pub const CUT_OFF: Self = Self {
        ranges: Ranges::CutOff,
        general: false,
    };

    /// Stochastic ranges drawn for the lights from `first` on over `interleave` x `interleave`
    /// pixel classes (1: none).
    pub fn stochastic(first: u32, interleave: u32) -> Self {
        Self {
            ranges: Ranges::Stochastic {
                first,
                interleave: interleave.max(1),
            },
            general: false,
        }
    }

    /// The lighting grid hierarchy's bands, handing over across `ramp`.
    pub fn hierarchy(ramp: f32) -> Self {
        Self {
            ranges: Ranges::Hierarchy { ramp },
            general: false,
        }
    }

    /// The model of a scene whose lights from `first` on take their ranges from `rule` (the
    /// lights before are the scene's own, of their own radii).
    pub fn of_rule(rule: &RadiusRule, first: u32) -> Self {
        match (rule, rule.hierarchy_params()) {
            (RadiusRule::Stochastic { interleave, .. }, _) => Self::stochastic(first, *interleave),
            (_, Some(p)) => Self::hierarchy(p.ramp as f32),
            _ => Self::CUT_OFF,
        }
    }

    /// This model shaded by the general model at every light.
    pub fn general(self) -> Self {
        Self {
            general: true,
            ..self
        }
    }

    /// The ramp of the hierarchy's bands the frame carries (the papers' where the model has no
    /// hierarchy).
    pub fn band_ramp(&self) -> f32 {
        match self.ranges {
            Ranges::Hierarchy { ramp } => ramp,
            _ => DEFAULT_BAND_RAMP,
        }
    }

    /// The path shading takes for `light_count` lights, of which `point_lights` says whether
    /// every one is a windowed point light as uploaded.
    pub fn path(&self, point_lights: bool, light_count: u32) -> LightPath {
        if self.general || !point_lights {
            return LightPath::General;
        }
        match self.ranges {
            Ranges::CutOff => LightPath::Points,
            // Interleaved classes, or lights left undrawn beside drawn ones, need the general
            // model's per-light reads.
            Ranges::Stochastic { first, interleave } => {
                if first == 0 && interleave <= 1 && light_count > 0 {
                    LightPath::StochasticPoints
                } else {
                    LightPath::General
                }
            }
            Ranges::Hierarchy { .. } => LightPath::BandPoints,
        }
    }

    /// Checks its values: an error naming the field and what it accepts.
    pub fn validate(&self) -> Result<(), String> {
        match self.ranges {
            Ranges::Hierarchy { ramp } if !(ramp > 1.0 && ramp <= 2.0) => Err(format!(
                "light model: hierarchy ramp = {ramp}: a band ramp above 1 and at most 2"
            )),
            Ranges::Stochastic { interleave: 0, .. } => {
                Err("light model: stochastic interleave = 0: pixel classes a side, from 1".into())
            }
            _ => Ok(()),
        }
    }
}

/// What a scene's lights are shaded by: the frame's flags (`FRAME_FLAG_POINT_LIGHTS` and its
/// kind) and the `POINT_LIGHTS`, `STOCHASTIC_POINTS` and `BAND_POINTS` override constants of every
/// shading pipeline (`shaders/common/shading.wgsl`), made from a [`LightModel`] and the lights.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LightPath {
    /// The general model: each light's kind, cone, alpha and interleaving read.
    General,
    /// Windowed point lights.
    Points,
    /// Point lights with stochastic ranges, one a light, shaded `max(1 / d^2, alpha)` inside
    /// them.
    StochasticPoints,
    /// The hierarchy's point lights, each shaded with its band times `1 / d^2`.
    BandPoints,
}

impl LightPath {
    /// Its bits of the frame's flags.
    pub fn frame_flags(self) -> u32 {
        match self {
            Self::General => 0,
            Self::Points => FRAME_FLAG_POINT_LIGHTS,
            Self::StochasticPoints => FRAME_FLAG_POINT_LIGHTS | FRAME_FLAG_STOCHASTIC_POINTS,
            Self::BandPoints => FRAME_FLAG_POINT_LIGHTS | FRAME_FLAG_BAND_POINTS,
        }
    }

    /// Every bit of the frame's flags a path may set.
    pub const FLAGS: u32 =
        FRAME_FLAG_POINT_LIGHTS | FRAME_FLAG_STOCHASTIC_POINTS | FRAME_FLAG_BAND_POINTS;

    /// The shading pipelines' override constants for it.
    pub fn constants(self) -> [(&'static str, f64); 3] {
        let on = |b: bool| f64::from(u8::from(b));
        [
            ("POINT_LIGHTS", on(self != Self::General)),
            ("STOCHASTIC_POINTS", on(self == Self::StochasticPoints)),
            ("BAND_POINTS", on(self == Self::BandPoints)),
        ]
    }

    /// Whether every light is shaded as a point light (the short path).
    pub fn point_lights(self) -> bool {
        self != Self::General
    }

    /// Its name in messages.
    pub fn name(self) -> &'static str {
        match self {
            Self::General => "general lights",
            Self::Points => "windowed point lights",
            Self::StochasticPoints => "point lights with stochastic ranges",
            Self::BandPoints => "point lights with hierarchy bands",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_path_follows_the_model_and_the_lights() {
        let m = LightModel::CUT_OFF;
        assert_eq!(m.path(true, 4), LightPath::Points);
        assert_eq!(m.path(false, 4), LightPath::General);
        assert_eq!(m.general().path(true, 4), LightPath::General);
        assert_eq!(
            LightModel::stochastic(0, 1).path(true, 4),
            LightPath::StochasticPoints
        );
        assert_eq!(
            LightModel::stochastic(0, 2).path(true, 4),
            LightPath::General
        );
        assert_eq!(
            LightModel::stochastic(1, 1).path(true, 4),
            LightPath::General
        );
        assert_eq!(
            LightModel::hierarchy(1.5).path(true, 4),
            LightPath::BandPoints
        );
        assert_eq!(
            LightModel::hierarchy(1.5).path(false, 4),
            LightPath::General
        );
        assert_eq!(LightModel::hierarchy(1.25).band_ramp(), 1.25);
        assert_eq!(LightModel::CUT_OFF.band_ramp(), DEFAULT_BAND_RAMP);
        assert!(
            LightModel::hierarchy(2.5)
                .validate()
                .unwrap_err()
                .contains("ramp = 2.5")
        );
        for p in [
            LightPath::General,
            LightPath::Points,
            LightPath::StochasticPoints,
            LightPath::BandPoints,
        ] {
            assert_eq!(p.frame_flags() & !LightPath::FLAGS, 0);
            assert_eq!(p.constants()[0].1 == 1.0, p.point_lights());
        }
    }
}
