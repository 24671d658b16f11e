//! The image being accumulated: per-pixel f64 sums in 4×4-tile-major order, so the tiles of
//! one pass can be written in parallel without locks.

use glam::Vec3;

pub const TILE: u32 = 4;

/// Where each pixel lives in tile-major order.
#[derive(Clone, Copy, Debug)]
pub struct TileLayout {
    pub width: u32,
    pub height: u32,
    tiles_x: u32,
}

impl TileLayout {
    pub fn new(width: u32, height: u32) -> Self {
        TileLayout {
            width,
            height,
            tiles_x: width.div_ceil(TILE),
        }
    }

    pub fn tile_count(&self) -> usize {
        (self.tiles_x * self.height.div_ceil(TILE)) as usize
    }

    /// Pixel coordinates of lane `lane` of tile `tile`, or None past the image edge.
    pub fn lane_pixel(&self, tile: usize, lane: usize) -> Option<(u32, u32)> {
        let (tx, ty) = (tile as u32 % self.tiles_x, tile as u32 / self.tiles_x);
        let (x, y) = (
            tx * TILE + lane as u32 % TILE,
            ty * TILE + lane as u32 / TILE,
        );
        (x < self.width && y < self.height).then_some((x, y))
    }

    pub fn index(&self, x: u32, y: u32) -> usize {
        let tile = (y / TILE) * self.tiles_x + x / TILE;
        (tile * 16 + (y % TILE) * TILE + x % TILE) as usize
    }
}

#[derive(Clone, Debug)]
pub struct Film {
    pub layout: TileLayout,
    /// Sum of samples, tile-major: tile t owns `sum[16 t .. 16 t + 16]`, lane = 4·dy + dx.
    pub sum: Vec<[f64; 3]>,
    /// Samples per pixel accumulated so far (every pixel gets one per pass).
    pub spp: u64,
}

impl Film {
    pub fn new(width: u32, height: u32) -> Self {
        let layout = TileLayout::new(width, height);
        Film {
            layout,
            sum: vec![[0.0; 3]; layout.tile_count() * 16],
            spp: 0,
        }
    }

    /// The mean image in scan-line order.
    pub fn mean(&self) -> Image {
        let inv = if self.spp == 0 {
            0.0
        } else {
            1.0 / self.spp as f64
        };
        let TileLayout { width, height, .. } = self.layout;
        let mut pixels = Vec::with_capacity((width * height) as usize);
        for y in 0..height {
            for x in 0..width {
                let s = self.sum[self.layout.index(x, y)];
                pixels.push([s[0] * inv, s[1] * inv, s[2] * inv]);
            }
        }
        Image {
            width,
            height,
            pixels,
        }
    }
}

/// An RGB image in scan-line order, f64 per channel: what metrics and outputs consume.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f64; 3]>,
}

impl Image {
    pub fn pixel(&self, x: u32, y: u32) -> Vec3 {
        let p = self.pixels[(y * self.width + x) as usize];
        Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32)
    }
}
