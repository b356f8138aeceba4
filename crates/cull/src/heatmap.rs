//! Heatmaps of list lengths, in the manner of the Forward+ paper's figure 2b (Harada, McKee,
//! Yang 2012): lights per tile (or per cluster of one depth slice, or the most over all slices)
//! and lights evaluated per pixel, colour-coded on one scale with a colour bar at the right.

use image::{Rgb, RgbImage};

use crate::layout::GpuCullParams;

/// Width of the colour bar drawn at the right edge of every heatmap, in pixels.
pub const BAR: u32 = 12;

/// Colour of `t` in [0, 1]: dark blue, blue, cyan, green, yellow, red (a rainbow ramp like the
/// paper's); exactly black for "no lights".
pub fn color(t: f32) -> Rgb<u8> {
    const STOPS: [[f32; 3]; 6] = [
        [0.05, 0.05, 0.35],
        [0.0, 0.3, 1.0],
        [0.0, 0.9, 0.9],
        [0.1, 0.85, 0.1],
        [1.0, 0.9, 0.0],
        [0.9, 0.05, 0.05],
    ];
    let x = t.clamp(0.0, 1.0) * (STOPS.len() - 1) as f32;
    let i = (x.floor() as usize).min(STOPS.len() - 2);
    let f = x - i as f32;
    let c = |k: usize| ((STOPS[i][k] * (1.0 - f) + STOPS[i + 1][k] * f) * 255.0).round() as u8;
    Rgb([c(0), c(1), c(2)])
}

fn shade(n: u32, max: u32) -> Rgb<u8> {
    if n == 0 {
        Rgb([0, 0, 0])
    } else {
        color(n as f32 / max.max(1) as f32)
    }
}

fn with_bar(mut img: RgbImage, w: u32, h: u32) -> RgbImage {
    for y in 0..h {
        let c = color(1.0 - y as f32 / (h.max(2) - 1) as f32);
        for x in w..w + BAR {
            img.put_pixel(x, y, c);
        }
    }
    img
}

/// Per-pixel heatmap of `counts` (`w` x `h`, rows from the top) on the scale [0, `max`];
/// pixels with no lights are black.
pub fn pixels(counts: &[u32], w: u32, h: u32, max: u32) -> RgbImage {
    let img = RgbImage::from_fn(w + BAR, h, |x, y| {
        if x < w {
            shade(counts[(y * w + x) as usize], max)
        } else {
            Rgb([0, 0, 0])
        }
    });
    with_bar(img, w, h)
}

/// Per-tile list lengths from every bin's (`CullOutput::bin_lengths`): for tiled strategies
/// the tile's list; for clusters (and z-binning's cells) the list of `slice`, or with `None`
/// the longest list over the tile's slices.
pub fn tile_counts(p: &GpuCullParams, lengths: &[u32], slice: Option<u32>) -> Vec<u32> {
    let tiles = (p.tiles_x * p.tiles_y) as usize;
    (0..tiles)
        .map(|t| match slice {
            Some(s) if p.slices > 1 => lengths[s.min(p.slices - 1) as usize * tiles + t],
            _ => (0..p.slices as usize)
                .map(|s| lengths[s * tiles + t])
                .max()
                .unwrap_or(0),
        })
        .collect()
}

/// Per-tile heatmap at image resolution (`w` x `h`), on the scale [0, `max`], with one-pixel
/// tile borders darkened so the grid shows.
pub fn tiles(p: &GpuCullParams, counts: &[u32], w: u32, h: u32, max: u32) -> RgbImage {
    let img = RgbImage::from_fn(w + BAR, h, |x, y| {
        if x >= w {
            return Rgb([0, 0, 0]);
        }
        let t = (y / p.tile_size) * p.tiles_x + x / p.tile_size;
        let Rgb([r, g, b]) = shade(counts[t as usize], max);
        if x % p.tile_size == 0 || y % p.tile_size == 0 {
            Rgb([r / 2, g / 2, b / 2])
        } else {
            Rgb([r, g, b])
        }
    });
    with_bar(img, w, h)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_is_monotone_in_hue_and_ends_red() {
        assert_eq!(color(1.0), Rgb([230, 13, 13]));
        assert_eq!(shade(0, 10), Rgb([0, 0, 0]));
        assert_ne!(shade(1, 10), Rgb([0, 0, 0]));
    }
}
