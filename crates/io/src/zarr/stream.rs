//! A level of an OME-Zarr store read a box at a time through a bounded cache of
//! decoded chunks (issue 31: "streams its chunks into the bricks"), so the level never
//! sits whole in memory.
//!
//! The cache is `zarrs`' own [`ChunkCacheDecodedLruSizeLimit`] (an LRU bounded in
//! bytes, on `moka`, whose `try_get_with` decodes a chunk once when several threads ask
//! for it at the same time). Chunks are decoded with a concurrency target of 1, so a
//! decode never enters rayon: a rayon worker waiting on another thread's decode of
//! a chunk can then never be the thread that must finish it (no deadlock).

use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

use zarrs::array::chunk_cache::{ChunkCache, ChunkCacheDecodedLruSizeLimit};
use zarrs::array::{Array, ArrayBytes, ArrayError, ArraySubset, CodecOptions};
use zarrs::storage::ReadableStorageTraits;

use super::{count_missing, level_notes, missing_note, open_level};
use crate::{IoError, ReadOptions};

/// The most voxels a streamed level may have: 2^33, the field's limit
/// (`glint_volume::MAX_FIELD_VOXELS`). A stream allocates nothing sized by the level's
/// voxel count (its cache is bounded; the field's largest table, the macro cells, takes
/// 1/8 byte a voxel), so [`ReadOptions::max_voxels`], the guard of the readers that
/// hold a volume whole, bounds its chunks, not the level.
pub const STREAM_MAX_VOXELS: u64 = 1 << 33;

/// A sample type a Zarr level may hold, read from its native-endian decoded bytes.
trait Element: Copy + Into<f64> {
    const SIZE: usize;
    fn at(bytes: &[u8], index: usize) -> Self;
}

macro_rules! element {
    ($($t:ty),*) => {$(
        impl Element for $t {
            const SIZE: usize = std::mem::size_of::<$t>();
            #[inline(always)]
            fn at(bytes: &[u8], index: usize) -> Self {
                let b = &bytes[index * Self::SIZE..(index + 1) * Self::SIZE];
                <$t>::from_ne_bytes(b.try_into().expect("SIZE bytes"))
            }
        }
    )*};
}
element!(u8, i8, u16, i16, u32, i32, f32, f64);

/// The stored types glint reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Stored {
    U8,
    I8,
    U16,
    I16,
    U32,
    I32,
    F32,
    F64,
}

impl Stored {
    /// The type of a level's data type name ([`super::LevelInfo::data_type`]).
    pub(crate) fn of(name: &str) -> Option<Stored> {
        Some(match name {
            "uint8" => Stored::U8,
            "int8" => Stored::I8,
            "uint16" => Stored::U16,
            "int16" => Stored::I16,
            "uint32" => Stored::U32,
            "int32" => Stored::I32,
            "float32" => Stored::F32,
            "float64" => Stored::F64,
            _ => return None,
        })
    }

    fn size(self) -> u64 {
        match self {
            Stored::U8 | Stored::I8 => 1,
            Stored::U16 | Stored::I16 => 2,
            Stored::U32 | Stored::I32 | Stored::F32 => 4,
            Stored::F64 => 8,
        }
    }
}

/// One level of an OME-Zarr store, open for reading boxes of voxels through a bounded
/// cache of decoded chunks (kept in their stored type). Made by [`Stream::open`];
/// `glint-volume` renders it as a field's source.
pub struct Stream {
    path: PathBuf,
    level: String,
    dims: [usize; 3],
    affine: [[f64; 4]; 4],
    stored: Stored,
    /// Axes of the array (time and channel first, read at index 0).
    ndim: usize,
    cache: ChunkCacheDecodedLruSizeLimit,
    array: Arc<Array<dyn ReadableStorageTraits>>,
    bound: u64,
    chunk_bytes: u64,
    options: CodecOptions,
    problem: OnceLock<String>,
    notes: Vec<String>,
}

impl Stream {
    /// Opens level [`ReadOptions::level`] of the store at `path`, with the checks
    /// [`super::read`] makes (metadata, the chunk shape against `max_voxels` before
    /// any chunk is decoded; the level's voxels against [`STREAM_MAX_VOXELS`]), and counts the chunks missing (a note, or under
    /// `strict` an error). The cache holds up to `2 * threads` layers of chunks (a
    /// layer: the chunks sharing a range of z, what one slab of the field's pass reads;
    /// two, as a slab may straddle two), no more than `limit` bytes, at least one
    /// chunk, and no more than the level's chunks.
    pub fn open(
        path: &Path,
        options: &ReadOptions,
        limit: u64,
        threads: usize,
    ) -> Result<Stream, IoError> {
        let mut o = open_level(path, options, STREAM_MAX_VOXELS.max(options.max_voxels))?;
        let l = o.level().clone();
        let stored = Stored::of(&l.data_type).expect("checked by open_level");
        let whole = ArraySubset::new_with_ranges(&o.ranges);
        let mut missing = (0, 0);
        count_missing(&o.array, &whole, &mut missing).map_err(|e| e.into_io(path, &l.path))?;
        missing_note(path, &l.path, missing, options.strict, &mut o.notes)?;
        o.notes.extend(level_notes(&o.all, o.chosen));
        let ndim = o.ranges.len();
        // check_chunks bounded the chunk's voxels by max_voxels (at most 2^33 voxels).
        let chunk_shape = o
            .array
            .chunk_shape(&vec![0; ndim])
            .map_err(|e| super::invalid(path, format!("level '{}': {e}", l.path)))?;
        let chunk_voxels = chunk_shape.iter().map(|c| c.get()).product::<u64>();
        let chunk_bytes = chunk_voxels.saturating_mul(stored.size());
        let grid = [0, 1, 2].map(|a| {
            let (n, c) = (o.ranges[ndim - 1 - a].end, chunk_shape[ndim - 1 - a].get());
            n.div_ceil(c).max(1)
        });
        let layer = chunk_bytes.saturating_mul(grid[0] * grid[1]);
        let all = layer.saturating_mul(grid[2]);
        let bound = layer
            .saturating_mul(2 * threads.max(1) as u64)
            .min(limit)
            .max(chunk_bytes)
            .min(all.max(chunk_bytes));
        let array = Arc::new(o.array);
        Ok(Stream {
            path: path.into(),
            level: l.path,
            dims: l.dims,
            affine: o.affine,
            stored,
            ndim,
            cache: ChunkCacheDecodedLruSizeLimit::new(array.clone(), bound),
            array,
            bound,
            chunk_bytes,
            options: CodecOptions::default().with_concurrent_target(1),
            problem: OnceLock::new(),
            notes: o.notes,
        })
    }

    /// Voxels along x, y, z.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Voxel index to world, row-major 4x4 (the level's scale and translation).
    pub fn affine(&self) -> [[f64; 4]; 4] {
        self.affine
    }

    /// What the reader says about the store: the same notes as [`super::read`]'s.
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// The most bytes of decoded chunks the cache holds.
    pub fn cache_bound(&self) -> u64 {
        self.bound
    }

    /// Bytes of one decoded chunk.
    pub fn chunk_bytes(&self) -> u64 {
        self.chunk_bytes
    }

    /// Decoded chunks the cache holds now.
    pub fn cached_chunks(&self) -> usize {
        self.cache.len()
    }

    /// Whether a value can be NaN or infinite (float data).
    pub fn is_float(&self) -> bool {
        matches!(self.stored, Stored::F32 | Stored::F64)
    }

    /// The first chunk that could not be read or decoded, as one line naming the
    /// store and level; `None` while every read succeeded.
    pub fn problem(&self) -> Option<String> {
        self.problem.get().cloned()
    }

    /// The values (`(1.0 * stored as f64 + 0.0) as f32`, the conversion of a volume
    /// read whole) of the voxels `lo .. lo + size`, x fastest, into `out` (`size`
    /// product long), coordinates clamped to the level's faces. A chunk that cannot be
    /// read leaves its part of the box 0 and sets [`Stream::problem`].
    pub fn read_box(&self, lo: [isize; 3], size: [usize; 3], out: &mut [f32]) {
        if size.contains(&0) {
            return;
        }
        if let Err(e) = match self.stored {
            Stored::U8 => self.read_typed::<u8>(lo, size, out),
            Stored::I8 => self.read_typed::<i8>(lo, size, out),
            Stored::U16 => self.read_typed::<u16>(lo, size, out),
            Stored::I16 => self.read_typed::<i16>(lo, size, out),
            Stored::U32 => self.read_typed::<u32>(lo, size, out),
            Stored::I32 => self.read_typed::<i32>(lo, size, out),
            Stored::F32 => self.read_typed::<f32>(lo, size, out),
            Stored::F64 => self.read_typed::<f64>(lo, size, out),
        } {
            let _ = self.problem.set(format!(
                "{}: level '{}': {e}",
                self.path.display(),
                self.level
            ));
        }
    }

    fn read_typed<T: Element>(
        &self,
        lo: [isize; 3],
        size: [usize; 3],
        out: &mut [f32],
    ) -> Result<(), ArrayError> {
        let n = self.ndim;
        let clamp = |x: isize, a: usize| x.clamp(0, self.dims[a] as isize - 1) as u64;
        let (mut start, mut shape) = (vec![0u64; n], vec![1u64; n]);
        for a in 0..3 {
            let first = clamp(lo[a], a);
            start[n - 1 - a] = first;
            shape[n - 1 - a] = clamp(lo[a] + size[a] as isize - 1, a) - first + 1;
        }
        let subset = ArraySubset::new_with_start_shape(start, shape)?;
        let Some(chunks) = self.array.chunks_in_array_subset(&subset)? else {
            return Err(ArrayError::InvalidChunkGridIndicesError(vec![]));
        };
        for c in &chunks.indices() {
            let cs = self.array.chunk_subset(&c)?;
            // The box's positions along each axis whose clamped voxel lies in the
            // chunk: a run, as clamping is monotone.
            let runs = [0, 1, 2].map(|a| {
                let (c0, cn) = (cs.start()[n - 1 - a], cs.shape()[n - 1 - a]);
                let at = |v: u64| {
                    if v == 0 {
                        0
                    } else if v >= self.dims[a] as u64 {
                        size[a]
                    } else {
                        (v as isize - lo[a]).clamp(0, size[a] as isize) as usize
                    }
                };
                (at(c0), at(c0 + cn), c0 as isize)
            });
            if runs.iter().any(|r| r.0 >= r.1) {
                continue;
            }
            let bytes = self.cache.retrieve_chunk_bytes(&c, &self.options)?;
            let ArrayBytes::Fixed(raw) = &*bytes else {
                return Err(ArrayError::InvalidChunkGridIndicesError(c.to_vec()));
            };
            let raw: &[u8] = raw;
            let (sx, sy) = (cs.shape()[n - 1] as usize, cs.shape()[n - 2] as usize);
            if (raw.len() as u64) < cs.num_elements() * T::SIZE as u64 {
                return Err(ArrayError::InvalidChunkGridIndicesError(c.to_vec()));
            }
            let local =
                |o: usize, a: usize| (clamp(lo[a] + o as isize, a) as isize - runs[a].2) as usize;
            for kk in runs[2].0..runs[2].1 {
                let k = local(kk, 2);
                for jj in runs[1].0..runs[1].1 {
                    let row = (k * sy + local(jj, 1)) * sx;
                    let o = (kk * size[1] + jj) * size[0];
                    for ii in runs[0].0..runs[0].1 {
                        let v: f64 = T::at(raw, row + local(ii, 0)).into();
                        out[o + ii] = (1.0 * v + 0.0) as f32;
                    }
                }
            }
        }
        Ok(())
    }
}
