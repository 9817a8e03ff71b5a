//! The process's memory budget for fields: a limit (set by `--memory-limit`, else a
//! share of the machine's memory) that every field's fixed data (its source's samples,
//! macro cells, page table) and brick pool are reserved from when it is built.

use std::sync::atomic::{AtomicU64, Ordering};

use glint_core::RenderError;

use super::brick::{BRICK_BYTES, BRICK_VOXELS};

/// The limit in bytes; 0 for the default.
static LIMIT: AtomicU64 = AtomicU64::new(0);

/// Bytes reserved by the fields alive.
static RESERVED: AtomicU64 = AtomicU64::new(0);

/// What the process needs besides the fields: the binary and its libraries, thread
/// stacks, the image and the classification of a 512x512 frame (the MNI152 bench scene
/// renders with a peak RSS of about 40 MiB over its volume's data).
pub const PROCESS_OVERHEAD: u64 = 64 << 20;

/// Share of the machine's memory the default limit takes: three quarters, leaving the
/// rest to the system and other programs.
const DEFAULT_SHARE: (u64, u64) = (3, 4);

/// The default limit where the machine's memory is unknown.
const FALLBACK_LIMIT: u64 = 8 << 30;

/// The fewest brick slots a pool may have: enough for the bricks one 16x16 tile of rays
/// reads on each of a few threads (a tile crosses tens of bricks).
pub const MIN_BRICK_SLOTS: u32 = 256;

/// A volume whose every brick fits in this (256 MiB: every brick of a volume of 18
/// million voxels, the MNI152 template's 8.7 million among them) gets them all by
/// default, so small volumes never evict.
pub const DEFAULT_POOL_FLOOR: u64 = 256 << 20;

/// The least the default pool of a larger volume takes: 128 MiB, some 2,300 bricks,
/// room for the bricks a 512x512 frame's tiles read at once many times over.
pub const DEFAULT_POOL_LEAST: u64 = 128 << 20;

/// The bricks a pool takes when no limit was set, for a field of `bricks` bricks and
/// `fixed` bytes of fixed data: all of them when they fit in [`DEFAULT_POOL_FLOOR`];
/// else half the bytes of the fixed data (its samples, mostly), or
/// [`DEFAULT_POOL_LEAST`] if more. A 16-bit volume then renders within about 1.5 times
/// its bytes plus the process and the frame's transients (issue 31 asks for 2.5x; a
/// brick costs 14 bytes a voxel, so building every brick of a large volume would take
/// 7x), evicting the bricks rays left behind; `--memory-limit` gives the pool more
/// room, up to every brick. Eviction changes no image (a frame with a 4-brick pool
/// equals a roomy one bit for bit), only the time spent rebuilding.
fn default_pool_slots(fixed: u64, bricks: u64) -> u64 {
    if bricks.saturating_mul(BRICK_BYTES) <= DEFAULT_POOL_FLOOR {
        bricks
    } else {
        (fixed / 2).max(DEFAULT_POOL_LEAST) / BRICK_BYTES
    }
}

/// The most slots a pool can address (slot offsets are i32 voxel indices).
const MAX_SLOTS: u64 = (i32::MAX as u64) / BRICK_VOXELS as u64;

/// Sets the memory limit of the fields built from now on (`None`: the default).
pub fn set_memory_limit(bytes: Option<u64>) {
    LIMIT.store(bytes.unwrap_or(0), Ordering::Relaxed);
}

/// The memory limit in force: the one set by [`set_memory_limit`], else three quarters
/// of the machine's physical memory (8 GiB where it cannot be read).
pub fn memory_limit() -> u64 {
    match LIMIT.load(Ordering::Relaxed) {
        0 => machine_memory()
            .map(|m| m / DEFAULT_SHARE.1 * DEFAULT_SHARE.0)
            .unwrap_or(FALLBACK_LIMIT),
        l => l,
    }
}

/// Total physical memory, from Linux's /proc/meminfo (`MemTotal: N kB`); `None`
/// elsewhere. Read by hand: one line of a text file, where a system-information crate
/// would bring dozens of dependencies for it.
fn machine_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kb.checked_mul(1024)
}

/// Bytes a field holds from the budget; given back when dropped.
pub(crate) struct Reservation(u64);

impl Drop for Reservation {
    fn drop(&mut self) {
        RESERVED.fetch_sub(self.0, Ordering::AcqRel);
    }
}

fn mib(b: u64) -> String {
    format!("{:.0} MiB", b as f64 / (1u64 << 20) as f64)
}

/// Reserves `fixed` bytes, `transient` more (the first pass's buffers, freed after it
/// but counted for the field's life so that the pass's peak stays within the limit,
/// and not used to size the default pool), and a pool for up to `bricks` bricks: as
/// many slots as the
/// budget leaves (all bricks and the dummy slot when they fit; without a limit set, no
/// more than [`default_pool_slots`]), at least
/// [`MIN_BRICK_SLOTS`] (or all, if fewer). Errors, naming the limit, when even that does
/// not fit.
pub(crate) fn reserve(
    fixed: u64,
    transient: u64,
    bricks: usize,
) -> Result<(Reservation, u32), RenderError> {
    let limit = memory_limit();
    let mut want = (bricks as u64 + 1).min(MAX_SLOTS);
    let least = want.min(u64::from(MIN_BRICK_SLOTS));
    if LIMIT.load(Ordering::Relaxed) == 0 {
        want = want.min(default_pool_slots(fixed, want).max(least));
    }
    let mut current = RESERVED.load(Ordering::Acquire);
    loop {
        let room = limit
            .saturating_sub(current)
            .saturating_sub(PROCESS_OVERHEAD)
            .saturating_sub(fixed)
            .saturating_sub(transient);
        let slots = want.min(room / BRICK_BYTES);
        if slots < least {
            return Err(RenderError::Volume(format!(
                "the volume needs at least {} ({} of samples and tables, {} of bricks, {} \
                 for the first pass's buffers, {} for the process{}), over the memory limit \
                 of {} (--memory-limit)",
                mib(fixed + transient + least * BRICK_BYTES + PROCESS_OVERHEAD + current),
                mib(fixed),
                mib(least * BRICK_BYTES),
                mib(transient),
                mib(PROCESS_OVERHEAD),
                if current > 0 {
                    format!(", {} for other volumes", mib(current))
                } else {
                    String::new()
                },
                mib(limit)
            )));
        }
        let bytes = fixed + transient + slots * BRICK_BYTES;
        match RESERVED.compare_exchange(
            current,
            current + bytes,
            Ordering::AcqRel,
            Ordering::Acquire,
        ) {
            Ok(_) => return Ok((Reservation(bytes), slots as u32)),
            Err(now) => current = now,
        }
    }
}
