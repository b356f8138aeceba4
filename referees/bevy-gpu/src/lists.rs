//! Bevy's read-back cluster buffers as lists of the export's lights.

use bevy::light::cluster::Clusters;
use bevy::math::UVec3;
use manylights_bevy_referee::Result;

/// Words a cluster takes in Bevy's offsets-and-counts buffer: two `uvec4`.
const CLUSTER_WORDS: usize = 8;

/// One frame's lists: each cluster's lights (the export's indices, ascending).
#[cfg_attr(test, derive(Clone))]
pub struct Frame {
    pub dims: UVec3,
    pub near: f32,
    pub far: f32,
    pub lists: Vec<Vec<u32>>,
    /// Whether Bevy's next frame slices to the same far bound (set by the caller): under
    /// `ClusterFarZMode::MaxClusterableObjectRange` Bevy takes it from the farthest light it
    /// read back from an earlier frame, which lags the lights by two frames.
    pub steady_far: bool,
    /// The export's lights in Bevy's light buffer (Bevy leaves out those it finds invisible).
    pub held: usize,
    /// Entries the counts ask for (lights only).
    pub entries: u64,
    /// The index list buffer's length.
    pub capacity: u64,
    /// Entries past the index list's end: Bevy's populate pass does not write them.
    pub dropped: u64,
}

impl Frame {
    pub fn same_lists(&self, other: &Frame) -> bool {
        (self.dims, self.near, self.far, self.held)
            == (other.dims, other.near, other.far, other.held)
            && self.lists == other.lists
    }

    /// The lists as offsets (one more than clusters) and indices.
    pub fn csr(&self) -> (Vec<u32>, Vec<u32>) {
        let mut offsets = vec![0u32];
        let mut indices = Vec::new();
        for l in &self.lists {
            indices.extend_from_slice(l);
            offsets.push(indices.len() as u32);
        }
        (offsets, indices)
    }
}

/// The lists of `clusters`' grid from Bevy's buffers: `counts` per cluster (offset, point,
/// spot and rect light counts, then probe, volume and decal counts and a pad), `indices` the
/// light indices of all lists, `ids` the export's light of each of Bevy's light indices.
pub fn lists_of(
    counts: &[u32],
    indices: &[u32],
    ids: &[Option<u32>],
    clusters: &Clusters,
) -> Result<Frame> {
    let dims = clusters.dimensions;
    let n = (dims.x * dims.y * dims.z) as usize;
    if counts.len() < n * CLUSTER_WORDS {
        return Err(format!(
            "Bevy's offsets-and-counts buffer holds {} clusters for a {} x {} x {} grid",
            counts.len() / CLUSTER_WORDS,
            dims.x,
            dims.y,
            dims.z
        ));
    }
    let (mut entries, mut dropped) = (0u64, 0u64);
    let mut lists = Vec::with_capacity(n);
    for c in counts.chunks_exact(CLUSTER_WORDS).take(n) {
        if c[4..7].iter().any(|&k| k != 0) {
            return Err("Bevy's lists hold probes or decals; the export has lights only".into());
        }
        let (offset, len) = (c[0] as usize, (c[1] + c[2] + c[3]) as usize);
        entries += len as u64;
        let mut list = Vec::with_capacity(len);
        for at in offset..offset + len {
            let Some(&bevy_index) = indices.get(at) else {
                dropped += 1;
                continue;
            };
            match ids.get(bevy_index as usize) {
                Some(Some(light)) => list.push(*light),
                _ => {
                    return Err(format!(
                        "Bevy's list entry {at} is light {bevy_index}, which is none of the \
                         export's {} lights",
                        ids.len()
                    ));
                }
            }
        }
        list.sort_unstable();
        lists.push(list);
    }
    Ok(Frame {
        dims,
        near: clusters.near,
        far: clusters.far,
        lists,
        held: ids.iter().flatten().count(),
        steady_far: false,
        entries,
        capacity: indices.len() as u64,
        dropped,
    })
}
