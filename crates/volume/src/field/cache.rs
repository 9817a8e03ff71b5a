//! The bounded cache of built bricks: a pool of fixed-size slots (values and gradients)
//! and a page table from brick to slot, filled on first use by any thread.
//!
//! Readers (the ray caster's tiles, [`super::Field::value`]) hold a
//! [`crossbeam_epoch`] guard while they use a slot; a full pool evicts its oldest
//! bricks (first built, first out) by clearing their page entries and hands their slots
//! back only once every reader pinned at the time has unpinned (epoch-based
//! reclamation, Fraser 2004, "Practical lock-freedom", as crossbeam implements it), so
//! a slot is never rewritten under a reader. The pool is allocated zeroed and untouched
//! (the operating system maps its pages on first write), so its resident size is that
//! of the slots used: it comes from the system allocator, not the global one (see
//! [`Slots::zeroed`]).

use std::alloc::{GlobalAlloc, Layout, System};
use std::collections::VecDeque;
use std::ptr::NonNull;
use std::sync::atomic::{AtomicI32, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

use crossbeam_epoch::Guard;

use super::brick::{Recipe, BRICK_VOXELS};

/// A page entry of a brick that is not built.
pub(crate) const ABSENT: i32 = -1;

/// Zeroed memory for `len` values of `T` that threads write in disjoint slots.
struct Slots<T> {
    ptr: NonNull<T>,
    layout: Layout,
}

// SAFETY: the memory is plain data owned by the pool; which thread may write which slot
// is the cache's protocol (a slot is written only by the thread that took it from the
// allocator, before it is published), and reads go through raw pointers.
unsafe impl<T: Send> Send for Slots<T> {}
// SAFETY: as above; `&Slots` hands out only raw pointers and, in `slot_mut`, slices of a
// slot the caller owns exclusively.
unsafe impl<T: Sync> Sync for Slots<T> {}

impl<T> Slots<T> {
    /// `len` zeroed values (all-zero bits must be a valid `T`: f32 and i16 are).
    ///
    /// From [`System`] (glibc's `calloc`), not the global allocator: a pool is tens to
    /// hundreds of MiB, above glibc's largest mmap threshold (32 MiB on 64-bit,
    /// `DEFAULT_MMAP_THRESHOLD_MAX`, mallopt(3)), so `calloc` maps it afresh and skips
    /// clearing it (malloc/malloc.c, `__libc_calloc`: mmapped chunks are already zero),
    /// and only the pages of the slots used are ever touched. The glint binary's
    /// mimalloc instead hands back the memory of the previous volume's pool and must
    /// clear all of it: with `glint batch` that memset of the whole pool cost more per
    /// volume than building the bricks the views use (docs/performance.md, issue 32).
    fn zeroed(len: usize) -> Option<Slots<T>> {
        let layout = Layout::array::<T>(len.max(1)).ok()?;
        // SAFETY: the layout has a non-zero size (len >= 1, T is not zero-sized here).
        let ptr = unsafe { System.alloc_zeroed(layout) }.cast::<T>();
        Some(Slots {
            ptr: NonNull::new(ptr)?,
            layout,
        })
    }

    fn as_ptr(&self) -> *const T {
        self.ptr.as_ptr()
    }

    /// The `len` values from `start`.
    ///
    /// # Safety
    /// The range must be inside the allocation and no other thread may read or write
    /// it while the slice lives.
    #[allow(clippy::mut_from_ref)]
    unsafe fn slot_mut(&self, start: usize, len: usize) -> &mut [T] {
        // SAFETY: the caller's contract: in bounds and exclusive.
        unsafe { std::slice::from_raw_parts_mut(self.ptr.as_ptr().add(start), len) }
    }
}

impl<T> Drop for Slots<T> {
    fn drop(&mut self) {
        // SAFETY: allocated by `System` in `zeroed` with this layout.
        unsafe { System.dealloc(self.ptr.as_ptr().cast(), self.layout) }
    }
}

/// The allocator's state.
struct Alloc {
    /// Slots never used yet start here (slot 0 is the dummy: always zero, never a
    /// brick's).
    next: u32,
    /// Slots free for reuse.
    free: Vec<u32>,
    /// Bricks built, oldest first, with their slots.
    resident: VecDeque<(u32, u32)>,
}

/// The pool of brick slots and the page table.
pub(crate) struct BrickCache {
    values: Slots<f32>,
    gradients: Slots<[i16; 4]>,
    /// Per brick: the offset of its slot's first voxel (slot x [`BRICK_VOXELS`]), or
    /// [`ABSENT`].
    page: Box<[AtomicI32]>,
    /// Slots, with the dummy.
    slots: u32,
    alloc: Mutex<Alloc>,
    /// Slots handed back by the deferred frees of evictions.
    freed: Arc<Mutex<Vec<u32>>>,
    /// Slots evicted and not handed back yet.
    pending: Arc<AtomicUsize>,
    builds: AtomicU64,
    evictions: AtomicU64,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    // A panic while holding the lock leaves consistent data (every update is a push or
    // pop), so a poisoned lock is still usable.
    m.lock().unwrap_or_else(|e| e.into_inner())
}

impl BrickCache {
    /// A cache of `slots - 1` bricks (at least 2 slots: the dummy and one) for a volume
    /// of `bricks` bricks; `None` when the pool cannot be allocated.
    pub(crate) fn new(bricks: usize, slots: u32) -> Option<BrickCache> {
        let slots = slots.max(2);
        let len = slots as usize * BRICK_VOXELS;
        Some(BrickCache {
            values: Slots::zeroed(len)?,
            gradients: Slots::zeroed(len)?,
            page: (0..bricks).map(|_| AtomicI32::new(ABSENT)).collect(),
            slots,
            alloc: Mutex::new(Alloc {
                next: 1,
                free: Vec::new(),
                resident: VecDeque::new(),
            }),
            freed: Arc::new(Mutex::new(Vec::new())),
            pending: Arc::new(AtomicUsize::new(0)),
            builds: AtomicU64::new(0),
            evictions: AtomicU64::new(0),
        })
    }

    /// The values of every slot: slot `s`'s voxel `v` at `s * BRICK_VOXELS + v`.
    #[inline(always)]
    pub(crate) fn values(&self) -> *const f32 {
        self.values.as_ptr()
    }

    /// The gradients, laid out as [`BrickCache::values`].
    #[inline(always)]
    pub(crate) fn gradients(&self) -> *const [i16; 4] {
        self.gradients.as_ptr()
    }

    /// The page table.
    #[inline(always)]
    pub(crate) fn page(&self) -> &[AtomicI32] {
        &self.page
    }

    /// Bricks built so far, and bricks evicted.
    pub(crate) fn counts(&self) -> (u64, u64) {
        (
            self.builds.load(Ordering::Relaxed),
            self.evictions.load(Ordering::Relaxed),
        )
    }

    /// Slots in use (built bricks and evicted ones not handed back).
    pub(crate) fn used(&self) -> usize {
        let a = lock(&self.alloc);
        a.next as usize - 1 - a.free.len()
    }

    /// The offset of brick `b`'s slot (`b` below the brick count), building it from
    /// `recipe` if it is absent; `None` when the pool is full of bricks readers may
    /// still use (an eviction has then been started). The offset stays valid while
    /// `guard` lives.
    #[inline(always)]
    pub(crate) fn offset(
        &self,
        b: usize,
        coords: [usize; 3],
        recipe: &Recipe,
        guard: &Guard,
    ) -> Option<i32> {
        let o = self.page[b].load(Ordering::Acquire);
        if o != ABSENT {
            return Some(o);
        }
        self.build(b, coords, recipe, guard)
    }

    #[cold]
    #[inline(never)]
    pub(crate) fn build(
        &self,
        b: usize,
        coords: [usize; 3],
        recipe: &Recipe,
        guard: &Guard,
    ) -> Option<i32> {
        let slot = self.take_slot(guard)?;
        let off = slot as usize * BRICK_VOXELS;
        // SAFETY: the slot is this thread's alone: it was never used, or it came back
        // from `free`, where a slot goes only when no page entry points to it and every
        // reader that could have read it has unpinned (the deferred free of `evict`), or
        // unpublished from a lost race below.
        let (v, g) = unsafe {
            (
                self.values.slot_mut(off, BRICK_VOXELS),
                self.gradients.slot_mut(off, BRICK_VOXELS),
            )
        };
        recipe.build(coords, v, g);
        // Release: a reader that loads the offset (Acquire) sees the brick's data.
        match self.page[b].compare_exchange(ABSENT, off as i32, Ordering::AcqRel, Ordering::Acquire)
        {
            Ok(_) => {
                lock(&self.alloc).resident.push_back((b as u32, slot));
                self.builds.fetch_add(1, Ordering::Relaxed);
                Some(off as i32)
            }
            Err(other) => {
                // Another thread built it first; nobody saw this copy.
                lock(&self.alloc).free.push(slot);
                Some(other)
            }
        }
    }

    /// A free slot, or `None` after starting an eviction when the pool is full.
    fn take_slot(&self, guard: &Guard) -> Option<u32> {
        let mut a = lock(&self.alloc);
        if a.free.is_empty() {
            let mut back = lock(&self.freed);
            a.free.append(&mut back);
        }
        if let Some(s) = a.free.pop() {
            return Some(s);
        }
        if a.next < self.slots {
            a.next += 1;
            return Some(a.next - 1);
        }
        // Full: evict the oldest eighth, unless an eviction is already on its way back.
        if self.pending.load(Ordering::Acquire) == 0 {
            let n = ((self.slots as usize - 1) / 8).max(1);
            self.evict(&mut a, n, guard);
        }
        None
    }

    /// Evicts the `n` oldest bricks: clears their page entries now and frees their
    /// slots once every thread pinned now has unpinned.
    fn evict(&self, a: &mut Alloc, n: usize, guard: &Guard) {
        let mut victims = Vec::with_capacity(n);
        while victims.len() < n {
            let Some((b, slot)) = a.resident.pop_front() else {
                break;
            };
            self.page[b as usize].store(ABSENT, Ordering::Release);
            victims.push(slot);
        }
        if victims.is_empty() {
            return;
        }
        self.evictions
            .fetch_add(victims.len() as u64, Ordering::Relaxed);
        self.pending.fetch_add(victims.len(), Ordering::AcqRel);
        let (freed, pending) = (self.freed.clone(), self.pending.clone());
        guard.defer(move || {
            let n = victims.len();
            lock(&freed).extend(victims);
            pending.fetch_sub(n, Ordering::AcqRel);
        });
        guard.flush();
    }

    /// Before a frame, from a thread that is not pinned: when fewer than a quarter of
    /// the slots are free, evicts the oldest bricks down to half the pool, and waits
    /// (a bounded number of tries) for evicted slots to come back, so the frame's new
    /// bricks find room.
    pub(crate) fn make_room(&self) {
        {
            let mut a = lock(&self.alloc);
            let cap = self.slots as usize - 1;
            let free = cap - (a.next as usize - 1) + a.free.len() + lock(&self.freed).len();
            if free < cap / 4 && self.pending.load(Ordering::Acquire) == 0 {
                let n = a.resident.len().saturating_sub(cap / 2);
                self.evict(&mut a, n, &crossbeam_epoch::pin());
            }
        }
        if crossbeam_epoch::is_pinned() {
            return;
        }
        // Each flush may advance the global epoch once; deferred frees run two epochs
        // after they were made, once no thread pinned before is still pinned.
        for _ in 0..64 {
            if self.pending.load(Ordering::Acquire) == 0 {
                break;
            }
            crossbeam_epoch::pin().flush();
            std::thread::yield_now();
        }
    }
}
