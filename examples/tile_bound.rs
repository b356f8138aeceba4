//! How tight can a list a tile get? At the Forward+ paper's configuration (the atrium, 3,072
//! light-field lights of radius 2.5 m, 1280 x 720), for tiles of 4, 8 and 16 pixels: lights
//! evaluated per light needed by gather's tile test with the side planes alone, with the box
//! test (`CullSettings::tile_boxes`), with the box of the tile's own surface points instead of
//! its frustum's, and the bound no list a tile can beat: the union of the exact sets of the
//! tile's pixels. The numbers behind docs/STRATEGIES.md, "The box test". CPU oracles over a
//! depth buffer from the GPU prepass (any Vulkan device; about 15 s in release):
//!
//!     cargo run --release --example tile_bound

use std::collections::BTreeSet;

use glam::DVec3;
use manylights_cull::geometry::{CullLight, tile_box, tile_keeps, tile_side_planes};
use manylights_cull::metrics::{exact_sets, surface_points};
use manylights_cull::{CullSettings, Strategy, cpu};
use manylights_gpu::layout::{GpuFrame, GpuLight};
use manylights_gpu::prepass::{DepthPrepass, depth_target};
use manylights_gpu::timing::GpuTimer;
use manylights_gpu::{GpuContext, GpuOptions, GpuScene, readback};
use manylights_scene::procedural::ProceduralScene;
use manylights_scene::{LightGenerator, LightSpec, RadiusRule};

fn main() -> anyhow::Result<()> {
    let ctx = GpuContext::new(&GpuOptions::default())?;
    let (w, h) = (1280u32, 720u32);
    let mut scene = ProceduralScene::from_name("atrium")?.build()?;
    scene.lights = LightSpec {
        generator: LightGenerator::LightField,
        count: 3072,
        seed: 2012,
        radius: RadiusRule::Fixed(2.5),
        intensity: 4.0,
        ..LightSpec::default()
    }
    .generate(&scene)?;
    let cam = scene.camera;
    let gs = GpuScene::upload(&ctx, &scene, &cam, w, h)?;
    let depth_tex = depth_target(&ctx, w, h);
    let view = depth_tex.create_view(&Default::default());
    let mut enc = ctx.device.create_command_encoder(&Default::default());
    DepthPrepass::new(&ctx, &gs).encode(&mut enc, &gs, &view, &mut GpuTimer::new(&ctx, 1));
    ctx.submit_and_wait(enc, "depth prepass")?;
    let depth: Vec<f32> = bytemuck::pod_collect_to_vec(&readback::read_texture(
        &ctx,
        &depth_tex,
        wgpu::TextureAspect::DepthOnly,
    )?);
    let frame = GpuFrame::new(&cam, w, h, scene.lights.len() as u32);
    let points = surface_points(&frame, &depth, w, h);
    let exact = exact_sets(&points, &scene.lights);
    let lights: Vec<GpuLight> = scene.lights.iter().map(GpuLight::from).collect();
    let needed: u64 = exact.iter().flatten().map(|e| e.len() as u64).sum();
    let view_from_world = frame.view_from_world.as_dmat4();
    println!("lights evaluated per light needed ({needed} needed in all):");
    for ts in [4u32, 8, 16] {
        let st = Strategy::TiledGather {
            tile_size: ts,
            coarse: 0,
        };
        let lists = |tile_boxes| {
            let settings = CullSettings {
                tile_boxes,
                ..CullSettings::for_camera(&cam)
            };
            let p = st.params(w, h, lights.len() as u32, &settings);
            let td = cpu::depth_bounds(&frame, &p, &depth, w, h).0;
            (p, td.clone(), cpu::gather(&frame, &p, &lights, &td))
        };
        let (p, td, planes) = lists(false);
        let (_, _, boxed) = lists(true);
        let tiles = (p.tiles_x * p.tiles_y) as usize;
        // Per tile: covered pixels, the union of their exact sets, the box of their points.
        let mut covered = vec![0u64; tiles];
        let mut union = vec![BTreeSet::new(); tiles];
        let mut lo = vec![DVec3::splat(f64::INFINITY); tiles];
        let mut hi = vec![DVec3::splat(f64::NEG_INFINITY); tiles];
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                let Some(e) = &exact[i] else { continue };
                let t = ((y / ts) * p.tiles_x + x / ts) as usize;
                covered[t] += 1;
                union[t].extend(e.iter().copied());
                let q = (view_from_world * points[i].expect("covered").extend(1.0)).truncate();
                lo[t] = lo[t].min(q);
                hi[t] = hi[t].max(q);
            }
        }
        let mut evaluated = [0u64; 4];
        for t in 0..tiles {
            let n = covered[t];
            if n == 0 {
                continue;
            }
            let tile = [t as u32 % p.tiles_x, t as u32 / p.tiles_x];
            let side = tile_side_planes(&frame, &p, tile);
            let bx = tile_box(&frame, &p, tile, &td[t]);
            let by_points = lights
                .iter()
                .filter(|l| {
                    let c = CullLight::new(&frame, l, p.slack);
                    let centre = c.center.as_dvec3();
                    let r = f64::from(c.radius + c.slack);
                    centre.clamp(lo[t], hi[t]).distance_squared(centre) <= r * r
                        && tile_keeps(&p, &c, &side, &bx, &td[t])
                })
                .count() as u64;
            evaluated[0] += n * planes.kept[t].len() as u64;
            evaluated[1] += n * boxed.kept[t].len() as u64;
            evaluated[2] += n * by_points;
            evaluated[3] += n * union[t].len() as u64;
        }
        let [a, b, c, d] = evaluated.map(|e| e as f64 / needed as f64);
        println!(
            "  {ts:>2} px: planes alone {a:.3}, box test {b:.3}, the points' box {c:.3}, \
             the tile's union of exact sets {d:.3}"
        );
    }
    Ok(())
}
