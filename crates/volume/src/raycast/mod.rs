//! The CPU ray caster: tiles of rays in parallel (rayon), trilinear samples at a fixed
//! step, empty-space skipping over macro cells, early ray termination.

mod caster;
mod features;
mod frame;
mod labels;
mod pick;
mod settings;
mod start;

#[cfg(target_arch = "x86_64")]
mod avx2;

#[cfg(target_arch = "x86_64")]
use avx2::Scratch;
/// The SIMD loops' per-thread buffers (none without them).
#[cfg(not(target_arch = "x86_64"))]
type Scratch = ();

pub use features::{PathFeatures, FEATURE_OPACITY};
pub(crate) use frame::CastLimits;
pub use labels::{LabelLook, LabelVolume};
pub use pick::{VolumeHit, PICK_OPACITY};
pub use settings::{FrameSettings, Kernel};

/// Accumulated opacity at which a ray stops (early ray termination, Levoy 1990).
pub const TERMINATION_OPACITY: f32 = 0.99;

/// Bisection steps refining an iso hit between two samples (2^-8 of a step).
const ISO_REFINE_STEPS: u32 = 8;

/// Edge of the square image tiles rendered as parallel tasks (a tile's rays read a
/// compact block of the volume that stays in the core's L2 cache).
const TILE: usize = 16;

/// Whether the CPU runs the SIMD compositing loop.
fn simd_supported() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        avx2::supported()
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}
