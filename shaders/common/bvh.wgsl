// The BVH of the scene's opaque triangles (manylights_gpu::bvh) and the any-hit shadow ray
// through it: whether the segment from `a` to `b` crosses an opaque triangle strictly
// between its ends (manylights_scene::ray states it in f64). An includer sets BVH_GROUP and
// BVH_BINDING, the bind group and first binding of the two buffers (the shading passes: group 0,
// bindings 3 and 4, scene.wgsl); BVH_STACK, the stack's depth, is the prelude's (the build
// checks the tree's depth against it).

struct BvhNode {
    // The box, slightly enlarged on upload so that the box test keeps every crossing the
    // triangle test finds; count: 0 for an inner node, its triangles for a leaf; first: the
    // first child (the second follows it) or the leaf's first triangle.
    lo: vec3<f32>,
    count: u32,
    hi: vec3<f32>,
    first: u32,
}

struct BvhTriangle {
    v0: vec4<f32>,
    v1: vec4<f32>,
    v2: vec4<f32>,
}

@group(BVH_GROUP) @binding(BVH_BINDING) var<storage, read> bvh_nodes: array<BvhNode>;
@group(BVH_GROUP) @binding(BVH_BINDING + 1u) var<storage, read> bvh_triangles: array<BvhTriangle>;

// The entry parameter of the segment o + t d, t in [0, 1], into box n (its inverse direction
// inv, finite), or a value above 1 where it misses the box.
fn bvh_box(n: BvhNode, o: vec3<f32>, inv: vec3<f32>) -> f32 {
    let a = (n.lo - o) * inv;
    let b = (n.hi - o) * inv;
    let near = min(a, b);
    let far = max(a, b);
    let t0 = max(max(near.x, near.y), max(near.z, 0.0));
    let t1 = min(min(far.x, far.y), min(far.z, 1.0));
    return select(2.0, t0, t0 <= t1);
}

// Möller and Trumbore's test: whether o + t d crosses triangle k at 0 < t < 1, inside or on
// its edges.
fn bvh_crosses(k: u32, o: vec3<f32>, d: vec3<f32>) -> bool {
    let tri = bvh_triangles[k];
    let e1 = tri.v1.xyz - tri.v0.xyz;
    let e2 = tri.v2.xyz - tri.v0.xyz;
    let p = cross(d, e2);
    let det = dot(e1, p);
    if det == 0.0 {
        return false;
    }
    let f = 1.0 / det;
    let s = o - tri.v0.xyz;
    let u = dot(s, p) * f;
    let q = cross(s, e1);
    let v = dot(d, q) * f;
    let t = dot(e2, q) * f;
    return u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0 && t < 1.0;
}

// Whether the segment from `a` to `b` is blocked (the first crossing found ends the walk). An
// inner node's two children are tested together where it is visited: the walk goes on into the
// nearer child the segment meets and keeps the farther on the stack only where it meets both,
// so that a node is loaded once it is known to be met and the stack holds no node that misses.
fn bvh_blocked(a: vec3<f32>, b: vec3<f32>) -> bool {
    let d = b - a;
    // A zero component's inverse as a large finite one, so that no product is 0 * inf.
    let safe = select(d, select(vec3<f32>(-1e-30), vec3<f32>(1e-30), d >= vec3<f32>(0.0)), abs(d) < vec3<f32>(1e-30));
    let inv = 1.0 / safe;
    var stack: array<u32, BVH_STACK>;
    var top = 0u;
    var n = bvh_nodes[0];
    if bvh_box(n, a, inv) > 1.0 {
        return false;
    }
    loop {
        if n.count > 0u {
            for (var k = n.first; k < n.first + n.count; k++) {
                if bvh_crosses(k, a, d) {
                    return true;
                }
            }
        } else {
            let c0 = bvh_nodes[n.first];
            let c1 = bvh_nodes[n.first + 1u];
            let t0 = bvh_box(c0, a, inv);
            let t1 = bvh_box(c1, a, inv);
            if t0 <= 1.0 && t1 <= 1.0 {
                // Both: the nearer now, the farther later.
                if t0 <= t1 {
                    stack[top] = n.first + 1u;
                    n = c0;
                } else {
                    stack[top] = n.first;
                    n = c1;
                }
                top += 1u;
                continue;
            }
            if t0 <= 1.0 {
                n = c0;
                continue;
            }
            if t1 <= 1.0 {
                n = c1;
                continue;
            }
        }
        if top == 0u {
            return false;
        }
        top -= 1u;
        n = bvh_nodes[stack[top]];
    }
    // (Not reached: naga asks for a return after the loop.)
    return false;
}
