//! The settings of a culling run that are not the strategy's own: the camera's depth range,
//! the slack, a capacity, the tile-mask budget and the box test.

use serde::{Deserialize, Serialize};

use crate::{CullError, layout};

/// Settings of a culling run that are not the strategy's own.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CullSettings {
    /// The camera's near plane distance.
    pub near: f32,
    /// The camera's far plane distance.
    pub far: f32,
    /// Conservative slack, relative to each light's distance (see `layout::DEFAULT_SLACK`).
    pub slack: f32,
    /// A deliberate cap on each list's length; lights beyond it are dropped and counted in
    /// [`crate::CullOutput::dropped`]. `None` (the default): lists are sized exactly, nothing dropped.
    pub capacity: Option<u32>,
    /// Most bytes of tile masks (a bit per tile and light) for this run: gather, 2.5D and tiled
    /// scatter use them where they fit (docs/STRATEGIES.md); `Some(0)` never. `None` (the
    /// default): the culler's own budget ([`crate::Culler::mask_budget`], [`crate::MASK_BUDGET`]).
    pub mask_budget: Option<u64>,
    /// Whether tile tests (gather, 2.5D, tiled scatter, z-binning's masks) also test each
    /// light's sphere against the view-space box of the tile's frustum between its depth
    /// bounds (true, the default; docs/STRATEGIES.md, "The box test"). The side planes test a
    /// sphere as if it were a cube: false keeps the planes alone, for ablations.
    #[serde(default = "default_tile_boxes")]
    pub tile_boxes: bool,
    /// Culling by visibility: after the lists, `cull.occlusion` drops from each bin's list the
    /// lights one of the scene's occluders hides from every point of the bin's cell
    /// ([`crate::blocks::occlusion`]; the occluders from [`crate::Culler::set_occluders`]).
    /// Lists of a list a bin only (not z-binning's). False by default.
    #[serde(default)]
    pub occlusion: bool,
}

fn default_tile_boxes() -> bool {
    true
}

impl CullSettings {
    /// The settings for `camera`, with the default slack and no capacity.
    pub fn for_camera(camera: &manylights_scene::Camera) -> Self {
        let (near, far) = camera.near_far();
        Self {
            near,
            far,
            slack: layout::DEFAULT_SLACK,
            capacity: None,
            mask_budget: None,
            tile_boxes: true,
            occlusion: false,
        }
    }

    /// Checks the values.
    pub fn validate(&self) -> Result<(), CullError> {
        if !(self.slack.is_finite() && self.slack >= 0.0) {
            return Err(CullError::InvalidParameter {
                field: "slack",
                value: self.slack.to_string(),
                accepted: "a finite value >= 0",
            });
        }
        if self.capacity == Some(0) {
            return Err(CullError::InvalidParameter {
                field: "capacity",
                value: "0".into(),
                accepted: "an integer >= 1, or none",
            });
        }
        Ok(())
    }
}
