// Culling by visibility's occluder test, the f32 twin of manylights_scene::occluders::hides:
// whether a convex polygon hides a point light from every point of a cell's convex hull (its
// eight corners), each corner beyond the polygon's plane and its segment to the light crossing
// the polygon, by `margin` plus a shadow ray's lift (SHADOW_OFFSET times the corner's largest
// coordinate's magnitude, at least 1) beyond the plane and inside every edge. The points a
// convex polygon hides from a point form a convex set, so the hull is hidden where its corners
// are. manylights_cull::occlusion::OccluderTest runs it over a batch of queries, its f64
// oracle's test; a list pass that drops hidden lights will call it.

struct Occluder {
    // Corners (xyz; w unused), counter-clockwise about the normal; the fourth unused where
    // normal.w is 3.
    corners: array<vec4<f32>, 4>,
    // Unit normal (xyz) and the corner count, 3 or 4 (w).
    normal: vec4<f32>,
}

// What a corner q of a cell must clear an occluder's plane and edges by: `margin` plus a shadow
// ray's lift there.
fn corner_spare(q: vec3<f32>, margin: f32) -> f32 {
    let a = abs(q);
    return margin + SHADOW_OFFSET * max(max(a.x, a.y), max(a.z, 1.0));
}

// Whether every corner of the cell lies beyond occluder o's plane on one side, each by its
// spare at `margin`: occluder_hides's first test, for any light on the other side, at any
// margin at least `margin`.
fn cell_beyond(o: Occluder, cell: array<vec3<f32>, 8>, margin: f32) -> bool {
    let n = o.normal.xyz;
    var side = 0.0;
    for (var c = 0u; c < 8u; c++) {
        let q = cell[c];
        let sq = dot(n, q - o.corners[0].xyz);
        if c == 0u {
            side = sign(sq);
        }
        if sq * side <= corner_spare(q, margin) {
            return false;
        }
    }
    return true;
}

// Whether o hides the light from every point of the cell (this file's opening comment).
fn occluder_hides(o: Occluder, light: vec3<f32>, cell: array<vec3<f32>, 8>, margin: f32) -> bool {
    let n = o.normal.xyz;
    let count = u32(o.normal.w);
    let sl = dot(n, light - o.corners[0].xyz);
    if abs(sl) <= margin {
        return false;
    }
    for (var c = 0u; c < 8u; c++) {
        let q = cell[c];
        let spare = corner_spare(q, margin);
        let sq = dot(n, q - o.corners[0].xyz);
        if sq * sign(sl) >= -spare {
            return false;
        }
        let x = light + (q - light) * (sl / (sl - sq));
        for (var i = 0u; i < count; i++) {
            let e0 = o.corners[i].xyz;
            let e1 = o.corners[(i + 1u) % count].xyz;
            let inward = normalize(cross(n, e1 - e0));
            if dot(inward, x - e0) <= spare {
                return false;
            }
        }
    }
    return true;
}
