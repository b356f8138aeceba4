//! Lights placed on surfaces (`OnSurfaces`) and as fixtures (`Fixtures`) in a closed room of
//! known planes: each where its rule puts it, spots aimed as it says, the same lights for the
//! same seed, their anchor normals those of their planes and gliding lights keeping their
//! distance from them, and bad values named.

use glam::Vec3;
use manylights_scene::{
    Aabb, Camera, LightGenerator, LightKind, LightSpec, Material, Motion, Primitive, RadiusRule,
    Scene,
};

/// A quad's two triangles with `normal` at every vertex.
fn quad(c: [Vec3; 4], normal: Vec3) -> Primitive {
    Primitive {
        positions: c.to_vec(),
        normals: vec![normal; 4],
        indices: vec![0, 1, 2, 0, 2, 3],
        material: 0,
    }
}

/// A room 8 x 3 x 6 m (x, y, z from 0), its normals facing in: floor, ceiling, four walls.
fn room() -> Scene {
    let (x, y, z) = (8.0, 3.0, 6.0);
    let v = Vec3::new;
    let primitives = vec![
        quad(
            [v(0., 0., 0.), v(x, 0., 0.), v(x, 0., z), v(0., 0., z)],
            Vec3::Y,
        ),
        quad(
            [v(0., y, 0.), v(0., y, z), v(x, y, z), v(x, y, 0.)],
            Vec3::NEG_Y,
        ),
        quad(
            [v(0., 0., 0.), v(0., y, 0.), v(x, y, 0.), v(x, 0., 0.)],
            Vec3::Z,
        ),
        quad(
            [v(0., 0., z), v(x, 0., z), v(x, y, z), v(0., y, z)],
            Vec3::NEG_Z,
        ),
        quad(
            [v(0., 0., 0.), v(0., 0., z), v(0., y, z), v(0., y, 0.)],
            Vec3::X,
        ),
        quad(
            [v(x, 0., 0.), v(x, y, 0.), v(x, y, z), v(x, 0., z)],
            Vec3::NEG_X,
        ),
    ];
    Scene {
        name: "room".into(),
        primitives,
        materials: vec![Material::new(Vec3::splat(0.7), 0.0)],
        lights: Vec::new(),
        camera: Camera::perspective(v(4., 1.5, 5.5), v(4., 1.5, 0.), 60.0, 0.1, 50.0),
        light_bounds: Aabb {
            min: Vec3::ZERO,
            max: v(x, y, z),
        },
    }
}

/// The distance from `p` to the room's plane whose inward normal is `n`.
fn from_plane(p: Vec3, n: Vec3) -> f32 {
    let d = [
        (Vec3::Y, p.y),
        (Vec3::NEG_Y, 3.0 - p.y),
        (Vec3::Z, p.z),
        (Vec3::NEG_Z, 6.0 - p.z),
        (Vec3::X, p.x),
        (Vec3::NEG_X, 8.0 - p.x),
    ];
    d.iter()
        .find(|(m, _)| m.dot(n) > 0.999)
        .map_or(f32::NAN, |&(_, d)| d)
}

/// The room's inward normal nearest `dir` horizontally (a wall's).
fn wall_of(dir: Vec3) -> Vec3 {
    let h = Vec3::new(dir.x, 0.0, dir.z).normalize();
    [Vec3::X, Vec3::NEG_X, Vec3::Z, Vec3::NEG_Z]
        .into_iter()
        .max_by(|a, b| a.dot(h).total_cmp(&b.dot(h)))
        .unwrap()
}

fn spec(generator: LightGenerator) -> LightSpec {
    LightSpec {
        generator,
        count: 2000,
        seed: 9,
        radius: RadiusRule::Fixed(1.0),
        spot_fraction: 1.0,
        ..LightSpec::default()
    }
}

#[test]
fn on_surfaces_lifts_every_light_within_its_range_and_aims_spots_out_of_the_surface() {
    let g = LightGenerator::OnSurfaces { offset: (0.1, 0.4) };
    let lights = spec(g).generate(&room()).unwrap();
    assert_eq!(lights.len(), 2000);
    assert_eq!(lights, spec(g).generate(&room()).unwrap(), "the same seed");
    let mut floor = 0;
    for l in &lights {
        // Its spot aims along its surface's normal, and it stands off that surface.
        let LightKind::Spot { direction: n, .. } = l.kind else {
            panic!("every light a spot")
        };
        let d = from_plane(l.position, n);
        assert!(
            (0.1 - 1e-4..=0.4 + 1e-4).contains(&d),
            "{:?}: {d} from its surface {n}",
            l.position
        );
        floor += usize::from(n.dot(Vec3::Y) > 0.999);
    }
    // Area-weighted: the floor is 48 of the room's 180 square metres.
    let share = floor as f64 / 2000.0;
    assert!((share - 48.0 / 180.0).abs() < 0.04, "{share}");
}

#[test]
fn fixtures_hang_under_ceilings_and_mount_on_walls() {
    let g = LightGenerator::Fixtures {
        drop: 0.2,
        on_walls: 0.25,
    };
    let lights = spec(g).generate(&room()).unwrap();
    assert_eq!(lights.len(), 2000);
    let (mut ceiling, mut walls) = (0, 0);
    for l in &lights {
        let LightKind::Spot { direction, .. } = l.kind else {
            panic!("every light a spot")
        };
        if direction.dot(Vec3::NEG_Y) > 0.999 {
            // Hanging under the ceiling.
            ceiling += 1;
            let d = from_plane(l.position, Vec3::NEG_Y);
            assert!(
                (d - 0.2).abs() < 1e-4,
                "{:?}: {d} under the ceiling",
                l.position
            );
        } else {
            // On a wall, aimed out of it and 30 degrees down.
            walls += 1;
            let n = wall_of(direction);
            let d = from_plane(l.position, n);
            assert!(
                (d - 0.2).abs() < 1e-4,
                "{:?}: {d} from its wall",
                l.position
            );
            assert!(
                (direction.dot(n) - 30f32.to_radians().cos()).abs() < 1e-4,
                "{direction}"
            );
            assert!((direction.y + 0.5).abs() < 1e-4, "{direction}");
        }
    }
    assert_eq!((ceiling, walls), (1500, 500));
}

#[test]
fn surface_placements_name_bad_values() {
    for (g, field) in [
        (
            LightGenerator::OnSurfaces { offset: (0.5, 0.1) },
            "lights.offset",
        ),
        (
            LightGenerator::OnSurfaces {
                offset: (-0.1, 0.1),
            },
            "lights.offset",
        ),
        (
            LightGenerator::Fixtures {
                drop: -1.0,
                on_walls: 0.5,
            },
            "lights.drop",
        ),
        (
            LightGenerator::Fixtures {
                drop: 0.1,
                on_walls: 1.5,
            },
            "lights.on_walls",
        ),
    ] {
        let e = spec(g).generate(&room()).unwrap_err().to_string();
        assert!(e.contains(field), "{g:?}: {e}");
    }
    // A floor alone has neither ceilings nor walls.
    let mut floor = room();
    floor.primitives.truncate(1);
    let e = spec(LightGenerator::Fixtures {
        drop: 0.1,
        on_walls: 0.5,
    })
    .generate(&floor)
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("Fixtures") && e.contains("downward-facing"),
        "{e}"
    );
}

/// The room's median irradiance from `lights`, measured apart from the rule: a regular grid of
/// points 10 cm apart on each of its six planes (every point of equal area, so the median is
/// area-weighted), each light's luminance over the squared distance (at least 1 cm) times the
/// cosine at the plane.
fn room_median_irradiance(lights: &[manylights_scene::Light]) -> f64 {
    let mut e = Vec::new();
    let planes = [
        (Vec3::Y, [Vec3::X, Vec3::Z], Vec3::ZERO),
        (Vec3::NEG_Y, [Vec3::X, Vec3::Z], Vec3::new(0., 3., 0.)),
        (Vec3::Z, [Vec3::X, Vec3::Y], Vec3::ZERO),
        (Vec3::NEG_Z, [Vec3::X, Vec3::Y], Vec3::new(0., 0., 6.)),
        (Vec3::X, [Vec3::Y, Vec3::Z], Vec3::ZERO),
        (Vec3::NEG_X, [Vec3::Y, Vec3::Z], Vec3::new(8., 0., 0.)),
    ];
    let extent = Vec3::new(8., 3., 6.);
    for (n, [a, b], origin) in planes {
        let (na, nb) = ((a.dot(extent) * 10.0) as u32, (b.dot(extent) * 10.0) as u32);
        for i in 0..na {
            for j in 0..nb {
                let p = origin + a * (i as f32 + 0.5) * 0.1 + b * (j as f32 + 0.5) * 0.1;
                let sum: f64 = lights
                    .iter()
                    .map(|l| {
                        let to = (l.position - p).as_dvec3();
                        let d2 = to.length_squared();
                        let cos = (to / d2.sqrt()).dot(n.as_dvec3()).max(0.0);
                        let c = l.color.as_dvec3() * f64::from(l.intensity);
                        (0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z) * cos / d2.max(1e-4)
                    })
                    .sum();
                e.push(sum);
            }
        }
    }
    e.sort_by(f64::total_cmp);
    e[e.len() / 2]
}

/// The exposure rule (`irradiance`): one intensity for every light, at which the room's median
/// surface point, measured apart on a grid of its planes, receives about the irradiance asked
/// for, at 2,000 lights (each measured) and at 16,000 (4,096 drawn); the intensity falls as one
/// over the count; radii by threshold follow the intensity; the lights' places are those of the
/// spec without the rule, and a spec without it serialises as before.
#[test]
fn the_exposure_rule_lights_the_median_surface_point_as_asked() {
    let base = LightSpec {
        spot_fraction: 0.0,
        radius: RadiusRule::Threshold(0.05),
        ..spec(LightGenerator::OnSurfaces {
            offset: (0.05, 0.3),
        })
    };
    let mut intensities = Vec::new();
    for (count, irradiance) in [(2000, 1.0), (16000, 1.0), (2000, 0.25)] {
        let s = LightSpec {
            count,
            irradiance: Some(irradiance),
            ..base
        };
        let lights = s.generate(&room()).unwrap();
        let i = lights[0].intensity;
        assert!(lights.iter().all(|l| l.intensity == i), "one intensity");
        let e = room_median_irradiance(&lights);
        assert!(
            (0.85..1.15).contains(&(e / f64::from(irradiance))),
            "{count} lights, irradiance {irradiance}: the median point has {e}"
        );
        for l in &lights {
            assert_eq!(
                l.radius,
                (i * l.color.max_element() / 0.05).sqrt().max(1e-3)
            );
        }
        let plain = LightSpec { count, ..base }.generate(&room()).unwrap();
        assert!(
            plain
                .iter()
                .zip(&lights)
                .all(|(a, b)| a.position == b.position && a.color == b.color),
            "the rule moves no light"
        );
        intensities.push(i);
    }
    let ratio = intensities[0] / intensities[1];
    assert!(
        (7.0..9.0).contains(&ratio),
        "2,000 against 16,000 lights: {ratio}"
    );
    assert!((intensities[0] / intensities[2] - 4.0).abs() < 1e-3);
    let ron = ron::to_string(&base).unwrap();
    assert!(!ron.contains("irradiance"), "{ron}");
    for bad in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        let e = LightSpec {
            irradiance: Some(bad),
            ..base
        }
        .generate(&room())
        .unwrap_err()
        .to_string();
        assert!(e.contains("lights.irradiance"), "{bad}: {e}");
    }
}

/// Each light's anchor is the inward normal of the plane it was placed on (one of the room's,
/// the light at its lift or drop from it), and a glide moves it only across that plane: at every frame it is as far
/// from the plane as at home, within the circle's diameter of home. Volume generators anchor up.
#[test]
fn gliding_lights_keep_their_distance_from_the_surface_they_were_placed_on() {
    let glide = Motion::Glide {
        speed: 0.4,
        extent: 0.3,
    };
    for (g, lo, hi) in [
        (LightGenerator::OnSurfaces { offset: (0.1, 0.4) }, 0.1, 0.4),
        (
            LightGenerator::Fixtures {
                drop: 0.15,
                on_walls: 0.5,
            },
            0.15,
            0.15,
        ),
    ] {
        let room = room();
        let lights = spec(g).generate(&room).unwrap();
        let anchors = spec(g).anchors(&room).unwrap();
        assert_eq!(anchors.len(), lights.len(), "{g:?}");
        for (i, (l, n)) in lights.iter().zip(&anchors).enumerate() {
            let home = from_plane(l.position, *n);
            assert!(
                home >= lo - 1e-4 && home <= hi + 1e-4,
                "{g:?} light {i}: anchor {n}, {home} m from its plane"
            );
            for frame in [1u32, 20, 333, 5000] {
                let p = glide.position_on(i as u32, l.position, l.radius, *n, frame);
                assert!(
                    (from_plane(p, *n) - home).abs() < 1e-4,
                    "{g:?} light {i} frame {frame}: {} m from its plane, {home} at home",
                    from_plane(p, *n)
                );
                assert!((p - l.position).length() <= 0.6 + 1e-4);
            }
        }
    }
    let uniform = spec(LightGenerator::Uniform).anchors(&room()).unwrap();
    assert!(uniform.len() == 2000 && uniform.iter().all(|&n| n == Vec3::Y));
}
