//! A tile's rectangle of samples, and the lanes the coverage loops take at once.

use super::frame::Binned;

/// Samples the rasterizer tests at once along a row (one AVX2 vector of f32).
pub(super) const LANES: usize = 8;

/// Each lane's offset from the first sample of a group.
pub(super) const LANE_X: [f32; LANES] = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0];

/// A tile: origin and size in samples.
#[derive(Clone, Copy)]
pub(super) struct Rect {
    pub(super) x0: usize,
    pub(super) y0: usize,
    pub(super) w: usize,
    pub(super) h: usize,
}

impl Rect {
    /// Row length of the tile's sample buffers: a group of lanes starting at the last
    /// sample of a row stays inside the row.
    pub(super) fn stride(&self) -> usize {
        self.w + LANES
    }
}

/// The part of triangle `t`'s bounding box inside `rect`, `[x0, y0, x1, y1]`
/// inclusive, or `None` when they do not meet.
#[inline(always)]
pub(super) fn clip(t: &Binned, rect: Rect) -> Option<[usize; 4]> {
    let [bx0, by0, bx1, by1] = t.bbox.map(usize::from);
    let (x0, y0) = (bx0.max(rect.x0), by0.max(rect.y0));
    let (x1, y1) = (bx1.min(rect.x0 + rect.w - 1), by1.min(rect.y0 + rect.h - 1));
    (x0 <= x1 && y0 <= y1).then_some([x0, y0, x1, y1])
}
