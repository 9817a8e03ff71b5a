//! The size of a `path` scene's drag frames (issue 41, item 3): while the camera is
//! dragged, a `path` scene is drawn path-traced at one sample per pixel and denoised
//! by the built-in à-trous filter ([`glint_render::Denoise::Atrous`]), at the largest
//! size whose measured cost keeps the interaction target (>= 20 frames/s, p95
//! input-to-frame <= 150 ms on 2 cores): [`DRAG_TARGET_MS`] per frame. The cost is
//! the client's own running estimate of milliseconds per pixel of its last path drag
//! frames ([`DragCost`]); the size is clamped between [`MIN_DRAG_SIDE`] on the long
//! side and half size. When even the smallest would take more than
//! [`DRAG_LIMIT_MS`] and more than the client's half-size `local` drag frames take
//! (their own running estimate), the frame is that `local` one, so the viewer never
//! drags slower than it did; a path frame over the limit but cheaper than the `local`
//! frame is kept (on a loaded machine both are over the limit). Every
//! [`REPROBE_EVERY`] `local` frames one path frame of the smallest size measures
//! again (the camera or the classification may have made it cheaper).
//!
//! The size depends on time measured; the image for a size does not: a path drag
//! frame of the same scene at the same size is the same image (the path tracer and
//! the filter are deterministic per seed).

/// Milliseconds a path drag frame aims at: 25 frames/s of rendering, leaving the
/// rest of the 50 ms a frame may take at 20 frames/s to encoding, the socket and the
/// page.
pub const DRAG_TARGET_MS: f64 = 40.0;

/// Milliseconds the smallest path drag frame may be expected to take before drag
/// frames fall back to half-size `local` ones (unless those take longer still): one
/// frame at 20 frames/s.
pub const DRAG_LIMIT_MS: f64 = 50.0;

/// Smallest long side of a path drag frame, pixels (when half size is smaller, half
/// size).
pub const MIN_DRAG_SIDE: u32 = 96;

/// The long side of a path drag frame is a multiple of this (or the smallest or the
/// half size): the size does not change with every small change of the estimate.
pub const DRAG_SIDE_STEP: u32 = 16;

/// While drag frames fall back to `local`, one in this many is a path frame of the
/// smallest size, to measure the cost again.
pub const REPROBE_EVERY: u32 = 48;

/// Weight of the newest frame in the running estimate of milliseconds per pixel (an
/// exponential moving average: the estimate follows a change of the view within a
/// few frames).
const NEWEST_WEIGHT: f64 = 0.5;

/// How a drag frame of a `path` scene is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DragFrame {
    /// Path-traced at one sample per pixel and denoised, at this size.
    Path([u32; 2]),
    /// In `local` lighting at this size (half size): the path frame would be too
    /// slow.
    Local([u32; 2]),
}

/// Half of a full frame's size (at least 1 pixel per side): today's drag size.
pub fn half_size(full: [u32; 2]) -> [u32; 2] {
    full.map(|x| (x / 2).max(1))
}

/// `half` scaled so that its long side is `long` (each side at least 1 pixel).
fn scaled(half: [u32; 2], long: u32) -> [u32; 2] {
    let max = half[0].max(half[1]);
    if long >= max {
        return half;
    }
    let s = f64::from(long) / f64::from(max);
    half.map(|x| ((f64::from(x) * s).round() as u32).clamp(1, x))
}

/// The drag frame of a `path` scene whose full frames are `full` pixels, given the
/// estimated cost of a path drag frame in milliseconds per pixel (`None`: nothing
/// measured yet, a frame of the smallest size measures it) and of a half-size `local`
/// drag frame in milliseconds (`None`: not measured): the largest size (its long side
/// a multiple of [`DRAG_SIDE_STEP`], between [`MIN_DRAG_SIDE`] and half size)
/// expected within [`DRAG_TARGET_MS`]; half-size `local` when the smallest is
/// expected to take more than [`DRAG_LIMIT_MS`] and more than the `local` frame.
pub fn drag_frame(full: [u32; 2], ms_per_pixel: Option<f64>, local_ms: Option<f64>) -> DragFrame {
    let half = half_size(full);
    let long = half[0].max(half[1]);
    let smallest = scaled(half, MIN_DRAG_SIDE.min(long));
    let Some(cost) = ms_per_pixel.filter(|c| c.is_finite() && *c >= 0.0) else {
        return DragFrame::Path(smallest);
    };
    let pixels = |s: [u32; 2]| f64::from(s[0]) * f64::from(s[1]);
    let least = cost * pixels(smallest);
    if least > DRAG_LIMIT_MS && !local_ms.is_some_and(|l| least <= l) {
        return DragFrame::Local(half);
    }
    if cost * pixels(half) <= DRAG_TARGET_MS {
        return DragFrame::Path(half);
    }
    // The long side whose frame is expected to take the target: the pixels scale
    // with its square.
    let fit = f64::from(long) * (DRAG_TARGET_MS / (cost * pixels(half))).sqrt();
    let stepped = (fit as u32 / DRAG_SIDE_STEP) * DRAG_SIDE_STEP;
    DragFrame::Path(scaled(half, stepped.clamp(MIN_DRAG_SIDE.min(long), long)))
}

/// One client's running estimate of what its path drag frames cost, and the
/// [`DragFrame`] it chooses from it.
#[derive(Clone, Debug, Default)]
pub struct DragCost {
    /// Milliseconds per pixel of the path drag frames measured (a moving average).
    ms_per_pixel: Option<f64>,
    /// Milliseconds of the half-size `local` drag frames measured (a moving average).
    local_ms: Option<f64>,
    /// Drag frames drawn in `local` since the last path one.
    local_frames: u32,
}

impl DragCost {
    /// The estimate in milliseconds per pixel (`None`: nothing measured yet).
    pub fn ms_per_pixel(&self) -> Option<f64> {
        self.ms_per_pixel
    }

    /// The drag frame for full frames of `full` pixels ([`drag_frame`]); after
    /// [`REPROBE_EVERY`] `local` ones in a row, a path frame of the smallest size.
    pub fn choose(&mut self, full: [u32; 2]) -> DragFrame {
        match drag_frame(full, self.ms_per_pixel, self.local_ms) {
            DragFrame::Local(size) if self.local_frames + 1 < REPROBE_EVERY => {
                self.local_frames += 1;
                DragFrame::Local(size)
            }
            DragFrame::Local(_) => {
                self.local_frames = 0;
                drag_frame(full, None, None)
            }
            path => {
                self.local_frames = 0;
                path
            }
        }
    }

    /// The estimate of a half-size `local` drag frame in milliseconds (`None`: none
    /// measured yet).
    pub fn local_ms(&self) -> Option<f64> {
        self.local_ms
    }

    /// A path drag frame of `size` took `ms` milliseconds (rendering, features and
    /// filter): the estimate moves towards it. Frames that did not finish are not
    /// measured.
    pub fn measured(&mut self, size: [u32; 2], ms: f64) {
        let pixels = f64::from(size[0]) * f64::from(size[1]);
        if ms.is_finite() && ms >= 0.0 && pixels > 0.0 {
            average(&mut self.ms_per_pixel, ms / pixels);
        }
    }

    /// A half-size `local` drag frame took `ms` milliseconds.
    pub fn measured_local(&mut self, ms: f64) {
        if ms.is_finite() && ms >= 0.0 {
            average(&mut self.local_ms, ms);
        }
    }
}

/// `estimate` moved towards `newest` by [`NEWEST_WEIGHT`] (set to it when empty).
fn average(estimate: &mut Option<f64>, newest: f64) {
    *estimate = Some(match *estimate {
        Some(old) => old + NEWEST_WEIGHT * (newest - old),
        None => newest,
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    const FULL: [u32; 2] = [512, 512];

    #[test]
    fn nothing_measured_takes_the_smallest_path_frame() {
        assert_eq!(drag_frame(FULL, None, None), DragFrame::Path([96, 96]));
        // The aspect is kept; the long side is the minimum.
        assert_eq!(
            drag_frame([640, 320], None, None),
            DragFrame::Path([96, 48])
        );
        // Half size below the minimum: half size.
        assert_eq!(drag_frame([24, 24], None, None), DragFrame::Path([12, 12]));
        assert_eq!(drag_frame([1, 1], None, None), DragFrame::Path([1, 1]));
        // A cost that is not a number measures again.
        assert_eq!(
            drag_frame(FULL, Some(f64::NAN), None),
            DragFrame::Path([96, 96])
        );
    }

    #[test]
    fn a_cheap_scene_drags_at_half_size_and_a_dearer_one_smaller() {
        // 40 ms for 256x256: half size exactly.
        let at_half = DRAG_TARGET_MS / (256.0 * 256.0);
        assert_eq!(
            drag_frame(FULL, Some(at_half), None),
            DragFrame::Path([256, 256])
        );
        assert_eq!(
            drag_frame(FULL, Some(0.0), None),
            DragFrame::Path([256, 256])
        );
        // Four times the cost per pixel: a quarter of the pixels, half the side.
        assert_eq!(
            drag_frame(FULL, Some(4.0 * at_half), None),
            DragFrame::Path([128, 128])
        );
        // Just over: the side is stepped down to a multiple of 16.
        assert_eq!(
            drag_frame(FULL, Some(1.01 * at_half), None),
            DragFrame::Path([240, 240])
        );
        // Whatever the cost, the frame expected is within the target.
        for k in [1.1, 1.5, 2.0, 3.0, 5.0, 7.0] {
            let cost = k * at_half;
            let DragFrame::Path(s) = drag_frame(FULL, Some(cost), None) else {
                panic!("{k}: local")
            };
            let ms = cost * f64::from(s[0] * s[1]);
            assert!(ms <= DRAG_TARGET_MS, "{k}: {s:?} takes {ms} ms");
            assert!(s[0] % DRAG_SIDE_STEP == 0 && s[0] >= MIN_DRAG_SIDE, "{s:?}");
        }
        // A wide frame keeps its aspect.
        assert_eq!(
            drag_frame(
                [1024, 512],
                Some(4.0 * DRAG_TARGET_MS / (512.0 * 256.0)),
                None
            ),
            DragFrame::Path([256, 128])
        );
    }

    #[test]
    fn too_dear_even_at_the_smallest_falls_back_to_half_size_local() {
        let smallest = 96.0 * 96.0;
        // Over the target but within the limit at the smallest: the smallest.
        let within = 0.99 * DRAG_LIMIT_MS / smallest;
        assert_eq!(
            drag_frame(FULL, Some(within), None),
            DragFrame::Path([96, 96])
        );
        // Over the limit: today's frame.
        let over = 1.01 * DRAG_LIMIT_MS / smallest;
        assert_eq!(
            drag_frame(FULL, Some(over), None),
            DragFrame::Local([256, 256])
        );
        assert_eq!(
            drag_frame(FULL, Some(1e9), None),
            DragFrame::Local([256, 256])
        );
        // Over the limit but no dearer than the local frame (a loaded machine): the
        // smallest path frame, which is not slower than before.
        let least = over * smallest;
        let local = |ms: f64| drag_frame(FULL, Some(over), Some(ms));
        assert_eq!(local(least * 1.2), DragFrame::Path([96, 96]));
        assert_eq!(local(least * 0.8), DragFrame::Local([256, 256]));
        assert_eq!(local(f64::NAN), DragFrame::Local([256, 256]));
    }

    #[test]
    fn the_estimate_follows_the_frames_and_a_local_run_measures_again() {
        let mut c = DragCost::default();
        assert_eq!(c.choose(FULL), DragFrame::Path([96, 96]));
        // 96x96 in 200 ms (MNI152 on a loaded machine may): too dear.
        c.measured([96, 96], 200.0);
        let locals = (0..REPROBE_EVERY - 1).map(|_| c.choose(FULL));
        assert!(locals
            .into_iter()
            .all(|f| f == DragFrame::Local([256, 256])));
        assert_eq!(c.local_ms(), None);
        // Then one path frame of the smallest size measures again.
        assert_eq!(c.choose(FULL), DragFrame::Path([96, 96]));
        // Cheaper now (a zoom out): the estimate moves halfway per frame.
        let cheap = 0.9 * DRAG_TARGET_MS / (256.0 * 256.0);
        for _ in 0..16 {
            c.measured([96, 96], cheap * 96.0 * 96.0);
        }
        assert_eq!(c.choose(FULL), DragFrame::Path([256, 256]));
        // Frames not measured leave it alone.
        let before = c.ms_per_pixel();
        c.measured([0, 0], 5.0);
        c.measured([96, 96], f64::NAN);
        assert_eq!(c.ms_per_pixel(), before);
        // Dear again (200 ms), but the local frames take 300 ms: path stays.
        let mut c = DragCost::default();
        c.measured([96, 96], 200.0);
        assert_eq!(c.choose(FULL), DragFrame::Local([256, 256]));
        c.measured_local(300.0);
        assert_eq!(c.local_ms(), Some(300.0));
        assert_eq!(c.choose(FULL), DragFrame::Path([96, 96]));
        // The local frames get quicker (100 ms, moving halfway each): local again.
        c.measured_local(100.0);
        c.measured_local(100.0);
        assert_eq!(c.choose(FULL), DragFrame::Local([256, 256]));
    }
}
