//! llvmpipe's loop limit (`GpuContext::loop_limit`) as per-pixel loops over lights meet it: the
//! iterations of a loop as naga writes it (a `for`, with a function that returns early, as a
//! light's test) before the driver ends it; and the same loop with a loop inside a branch that
//! no invocation takes, which llvmpipe enters all the same (its lanes masked off) and counts: a
//! light's test may not hold a loop behind a runtime condition (the exact oracle's shadowed
//! test, `shaders/cull/per_pixel/exact_point.wgsl`, is chosen outside its loops for this).

use manylights_gpu::{GpuContext, GpuOptions, readback};
use wgpu::util::DeviceExt;

const PROBE: &str = r#"
@group(0) @binding(0) var<storage, read_write> out: array<u32>;
// x: the iterations asked for; y: whether the inner loop runs (0 here: it never does).
@group(0) @binding(1) var<uniform> n: vec4<u32>;
fn odd(k: u32) -> bool {
    if (k & 1u) == 0u {
        return false;
    }
    return true;
}
@compute @workgroup_size(8, 8)
fn plain(@builtin(local_invocation_index) li: u32) {
    var count = 0u;
    var odds = 0u;
    for (var k = 0u; k < n.x; k++) {
        count += 1u;
        if odd(k) {
            odds += 1u;
        }
    }
    out[li] = count;
    out[64u + li] = odds;
}
@compute @workgroup_size(8, 8)
fn branch(@builtin(local_invocation_index) li: u32) {
    var count = 0u;
    var inner = 0u;
    for (var k = 0u; k < n.x; k++) {
        count += 1u;
        if n.y != 0u {
            for (var j = 0u; j < n.y; j++) {
                inner += 1u;
            }
        }
    }
    out[li] = count;
    out[64u + li] = inner;
}
"#;

/// The iterations each of 64 invocations of entry point `entry` ran of `asked`.
fn iterations(ctx: &GpuContext, entry: &str, asked: u32) -> Vec<u32> {
    let d = &ctx.device;
    let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("loop_limit"),
        source: wgpu::ShaderSource::Wgsl(PROBE.into()),
    });
    let out = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("loop_limit.out"),
        size: 512,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let uniform = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("loop_limit.n"),
        contents: bytemuck::cast_slice(&[asked, 0, 0, 0]),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("loop_limit"),
        layout: None,
        module: &module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    });
    let group = d.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("loop_limit"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: out.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: uniform.as_entire_binding(),
            },
        ],
    });
    let mut enc = ctx.encoder("loop_limit");
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(1, 1, 1);
    }
    ctx.submit_and_wait(enc, "loop limit probe").unwrap();
    readback::read_buffer(ctx, &out, 0, 256)
        .unwrap()
        .chunks(4)
        .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

#[test]
fn loops_run_as_the_context_says_and_untaken_loops_count_on_llvmpipe() {
    let ctx =
        GpuContext::new(&GpuOptions::default()).expect("a Vulkan adapter (lavapipe is enough)");
    let asked = 200_000;
    let plain = iterations(&ctx, "plain", asked);
    let branch = iterations(&ctx, "branch", asked);
    println!(
        "{}: {} and {} of {asked} iterations",
        ctx.info.name, plain[0], branch[0]
    );
    for (what, ran) in [("plain", &plain), ("branch", &branch)] {
        assert!(ran.iter().all(|&r| r == ran[0]), "{what}: {ran:?}");
    }
    match ctx.loop_limit {
        None => {
            assert_eq!(
                plain[0], asked,
                "a driver without a loop limit ended a loop"
            );
            assert_eq!(
                branch[0], asked,
                "a driver without a loop limit ended a loop"
            );
        }
        Some(limit) => {
            assert_eq!(u64::from(plain[0]), limit, "llvmpipe's loop iterations");
            // Each iteration enters the untaken inner loop once: two counted.
            assert_eq!(
                u64::from(branch[0]),
                limit.div_ceil(2),
                "the untaken loop's count"
            );
        }
    }
}
