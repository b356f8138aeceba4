//! Culling strategies on a real Vulkan device (lavapipe in CI) against their CPU oracles and the
//! exact per-pixel oracle.

#[path = "../common/mod.rs"]
mod common;

mod cases;
mod exactness;
mod global_use;
mod lists;
mod msaa;
mod occlusion;
mod order;
mod pairs;
mod paths;
mod transparent;

use cases::*;

use std::collections::HashSet;

use glam::Vec3;
use manylights_cull::layout::{GpuCullParams, line_threads};
use manylights_cull::metrics::{ListMetrics, evaluate, exact_sets, surface_points};
use manylights_cull::record::{Buf, StepInfo};
use manylights_cull::{BinLists, CullSettings, Culler, Slicing, Strategy, cpu, geometry, scan};
use manylights_gpu::layout::{GpuFrame, GpuLight};
use manylights_gpu::timing::{GpuTimer, PassTiming};
use manylights_gpu::{GpuContext, readback};
use manylights_scene::procedural::{
    AtriumParams, CityParams, PillarsParams, ProceduralScene, TopdownParams,
};
use manylights_scene::{
    Camera, Light, LightGenerator, LightKind, LightSpec, Projection, RadiusRule, Scene,
};
use rand::{RngExt, SeedableRng};
