// Moving lights: the WGSL twin of manylights_scene::motion (see its module docs for the paths;
// that module is the oracle of this pass). Host side: manylights_gpu::motion. Each thread moves
// one light of [first, first + count) from its home position (binding 1, position and radius)
// to where it is at `time`, writing only the position of the scene's light; a glide reads each
// light's anchor normal (binding 3; a single unused entry for the other motions).
// Constants MOTION_STATIC, MOTION_ORBIT, MOTION_NOISE and MOTION_GLIDE come from the Rust
// definitions.

struct MotionParams {
    kind: u32,
    first: u32,
    count: u32,
    // Threads in one row of the dispatch grid (workgroups in x times 256).
    row: u32,
    speed: f32,
    time: f32,
    // A glide's circle radius (world units).
    extent: f32,
    _pad0: u32,
}

@group(0) @binding(0) var<uniform> motion: MotionParams;
@group(0) @binding(1) var<storage, read> home: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> moved: array<Light>;
@group(0) @binding(3) var<storage, read> anchor: array<vec4<f32>>;

const TAU: f32 = 6.283185307179586;

// A number in [0, 1) from a light's index and a salt, 24 bits.
fn hash01(index: u32, salt: u32) -> f32 {
    return f32(pcg(index * 8u + salt) >> 8u) / 16777216.0;
}

// Two unit tangents of the unit normal n (Duff et al. 2017), as manylights_scene::motion::tangents.
fn tangent_u(n: vec3<f32>) -> vec3<f32> {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    return vec3<f32>(1.0 + sign * n.x * n.x * a, sign * n.x * n.y * a, -sign * n.x);
}

fn tangent_v(n: vec3<f32>) -> vec3<f32> {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    return vec3<f32>(n.x * n.y * a, sign + n.y * n.y * a, -n.y);
}

fn motion_offset(index: u32, radius: f32, t: f32, i: u32) -> vec3<f32> {
    var a = 0.5 * radius;
    if (motion.kind == MOTION_GLIDE) {
        a = motion.extent;
    }
    if (motion.kind == MOTION_STATIC || motion.speed == 0.0 || a <= 0.0) {
        return vec3<f32>(0.0);
    }
    let w = motion.speed / a;
    if (motion.kind == MOTION_GLIDE) {
        let n = anchor[i].xyz;
        let p = TAU * hash01(index, 0u);
        let q = p + w * t;
        return a * ((cos(q) - cos(p)) * tangent_u(n) + (sin(q) - sin(p)) * tangent_v(n));
    }
    if (motion.kind == MOTION_ORBIT) {
        let p = TAU * hash01(index, 0u);
        let q = p + w * t;
        return a * vec3<f32>(cos(q) - cos(p), 0.0, sin(q) - sin(p));
    }
    var o = vec3<f32>(0.0);
    for (var k = 0u; k < 3u; k++) {
        let f = 0.5 + hash01(index, 1u + k);
        let p = TAU * hash01(index, 4u + k);
        o[k] = a * (sin(f * w * t + p) - sin(p));
    }
    return o;
}

@compute @workgroup_size(256)
fn animate(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * motion.row;
    if (i >= motion.count) {
        return;
    }
    let h = home[i];
    let index = motion.first + i;
    moved[index].position = h.xyz + motion_offset(index, h.w, motion.time, i);
}
