//! What one frame's shading counts in group 0's counters (binding 5, [`RAY_COUNT_SLOTS`]
//! words): the shadow rays it casts or the lights its pixels walk, each under its frame flag,
//! in a frame of its own.

use manylights_scene::Camera;

use super::{GpuScene, RAY_COUNT_SLOTS};
use crate::{GpuContext, GpuError};

impl GpuScene {
    /// The shadow rays `render` casts: the counters cleared, the frame uniform set for
    /// `camera` at `width` x `height` with [`crate::layout::FRAME_FLAG_COUNT_RAYS`] (shading
    /// with `SHADOWS` then adds one for each ray it casts), `render` run, the counters read back
    /// and summed, the frame set again without the flag. A frame that is timed must not count:
    /// each ray then writes to memory.
    pub fn count_rays<E: From<GpuError>>(
        &self,
        ctx: &GpuContext,
        view: (&Camera, u32, u32),
        render: impl FnOnce() -> Result<(), E>,
    ) -> Result<u64, E> {
        self.count(ctx, view, crate::layout::FRAME_FLAG_COUNT_RAYS, render)
    }

    /// The lights `render`'s shading walks, summed over its pixels (fragments, sample groups):
    /// each light whose distance a pixel's loop tests against its range, after whatever the
    /// loop narrows its list by first ([`crate::layout::FRAME_FLAG_COUNT_LIGHTS`]; the lists'
    /// own lengths count every light a list hands a pixel). As [`GpuScene::count_rays`], the
    /// counters cleared, the flag set for `render` and cleared after; a timed frame must not
    /// count.
    pub fn count_lights_walked<E: From<GpuError>>(
        &self,
        ctx: &GpuContext,
        view: (&Camera, u32, u32),
        render: impl FnOnce() -> Result<(), E>,
    ) -> Result<u64, E> {
        self.count(ctx, view, crate::layout::FRAME_FLAG_COUNT_LIGHTS, render)
    }

    /// Group 0's counters cleared, `render` run with the frame's `flag` set, and the counters'
    /// sum read back.
    fn count<E: From<GpuError>>(
        &self,
        ctx: &GpuContext,
        (camera, width, height): (&Camera, u32, u32),
        flag: u32,
        render: impl FnOnce() -> Result<(), E>,
    ) -> Result<u64, E> {
        let bytes = u64::from(RAY_COUNT_SLOTS) * 4;
        ctx.queue
            .write_buffer(&self.ray_counts, 0, &vec![0u8; bytes as usize]);
        self.set_view(ctx, camera, width, height, flag);
        let rendered = render();
        self.set_view(ctx, camera, width, height, 0);
        rendered?;
        let counts = crate::readback::read_buffer(ctx, &self.ray_counts, 0, bytes)?;
        Ok(bytemuck::cast_slice::<u8, u32>(&counts)
            .iter()
            .map(|&n| u64::from(n))
            .sum())
    }
}
