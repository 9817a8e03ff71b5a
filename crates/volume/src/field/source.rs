//! Where a field's samples come from: a [`Source`] hands out the physical values of any
//! box of voxels, so the field keeps the samples in their stored type (or in a chunked
//! store on disk) and converts only the boxes it builds.

use glint_io::zarr::Stream;
use glint_io::{Samples, Volume};

/// The samples of a field, read a box at a time.
///
/// A box may reach outside the volume: coordinates are clamped to its faces (the
/// voxel beyond a face is a copy of the face voxel), which is how the field's prefilter
/// treats the faces.
pub trait Source: Send + Sync {
    /// Samples along i, j, k.
    fn dims(&self) -> [usize; 3];

    /// Voxel index to world RAS+ mm, row-major 4x4.
    fn affine(&self) -> [[f64; 4]; 4];

    /// Bytes the source itself keeps in memory (counted against the memory budget).
    fn resident_bytes(&self) -> u64;

    /// Whether a physical value can be NaN or infinite (float samples, or a scale that
    /// overflows f32); the field then checks its pass over the volume for them, and
    /// when it meets one, finds the finite range in a pass of its own and passes again.
    fn may_be_non_finite(&self) -> bool;

    /// Physical values (`(slope * stored + intercept) as f32`) of the voxels
    /// `lo .. lo + size`, i fastest, into `out` (`size` product long), coordinates
    /// clamped to the volume. A source that cannot read part of the box (a chunk
    /// missing from a store) fills it with its fill value and reports it through
    /// [`Source::problem`].
    fn read(&self, lo: [isize; 3], size: [usize; 3], out: &mut [f32]);

    /// The first problem a [`Source::read`] met (an I/O error, a corrupt chunk), if
    /// any: a render that used the source then fails with it.
    fn problem(&self) -> Option<String> {
        None
    }
}

/// Clamps `x` to `0..n` (`n >= 1`).
#[inline(always)]
fn clamp(x: isize, n: usize) -> usize {
    x.clamp(0, n as isize - 1) as usize
}

/// Calls `row(out_row, src_start, x_map)` for every row of the box `lo .. lo + size`
/// of a volume of `dims`: `src_start` is the linear index of the row's clamped
/// (j, k) at i = 0. Shared by the sources that keep samples in memory.
pub(crate) fn for_each_row(
    dims: [usize; 3],
    lo: [isize; 3],
    size: [usize; 3],
    out: &mut [f32],
    mut row: impl FnMut(&mut [f32], usize),
) {
    let [nx, ny, nz] = dims;
    for (kk, slab) in out.chunks_exact_mut(size[0] * size[1]).enumerate() {
        let k = clamp(lo[2] + kk as isize, nz);
        for (jj, r) in slab.chunks_exact_mut(size[0]).enumerate() {
            let j = clamp(lo[1] + jj as isize, ny);
            row(r, nx * (j + ny * k));
        }
    }
}

/// Copies `src[start + clamp(lo_i + x)]` converted by `f` into each `out[x]`: the
/// clamped ends one at a time, the part inside the row as one slice.
#[inline(always)]
fn convert_row<T: Copy>(
    out: &mut [f32],
    src: &[T],
    start: usize,
    lo_i: isize,
    nx: usize,
    f: impl Fn(T) -> f32,
) {
    let n = out.len() as isize;
    // Output positions whose i lies inside the row.
    let a = (-lo_i).clamp(0, n) as usize;
    let b = (nx as isize - lo_i).clamp(0, n) as usize;
    if a < b {
        let first = (lo_i + a as isize) as usize;
        for (o, &x) in out[a..b]
            .iter_mut()
            .zip(&src[start + first..start + first + (b - a)])
        {
            *o = f(x);
        }
    }
    let edge = |x: usize| f(src[start + clamp(lo_i + x as isize, nx)]);
    for x in (0..a).chain(b.max(a)..out.len()) {
        out[x] = edge(x);
    }
}

impl Source for Volume {
    fn dims(&self) -> [usize; 3] {
        self.dims
    }

    fn affine(&self) -> [[f64; 4]; 4] {
        self.affine
    }

    fn resident_bytes(&self) -> u64 {
        let size = match &self.samples {
            Samples::U8(_) | Samples::I8(_) => 1,
            Samples::U16(_) | Samples::I16(_) => 2,
            Samples::U32(_) | Samples::I32(_) | Samples::F32(_) => 4,
            Samples::F64(_) => 8,
        };
        self.samples.len() as u64 * size
    }

    fn may_be_non_finite(&self) -> bool {
        let (s, b) = (self.slope, self.intercept);
        let fits = |lo: f64, hi: f64| [lo, hi].iter().all(|&x| ((s * x + b) as f32).is_finite());
        match &self.samples {
            Samples::U8(_) => !fits(0.0, 255.0),
            Samples::I8(_) => !fits(-128.0, 127.0),
            Samples::U16(_) => !fits(0.0, 65535.0),
            Samples::I16(_) => !fits(-32768.0, 32767.0),
            Samples::U32(_) => !fits(0.0, u32::MAX as f64),
            Samples::I32(_) => !fits(i32::MIN as f64, i32::MAX as f64),
            Samples::F32(_) | Samples::F64(_) => true,
        }
    }

    fn read(&self, lo: [isize; 3], size: [usize; 3], out: &mut [f32]) {
        physical_box(self, lo, size, out)
    }
}

/// [`Source::read`] of an in-memory volume: `(slope * stored as f64 + intercept) as
/// f32`, the conversion the field always made.
fn physical_box(v: &Volume, lo: [isize; 3], size: [usize; 3], out: &mut [f32]) {
    fn go<T: Copy + Into<f64>>(
        v: &Volume,
        s: &[T],
        lo: [isize; 3],
        size: [usize; 3],
        out: &mut [f32],
    ) {
        let (sl, b) = (v.slope, v.intercept);
        let nx = v.dims[0];
        for_each_row(v.dims, lo, size, out, |r, start| {
            convert_row(r, s, start, lo[0], nx, |x| (sl * x.into() + b) as f32)
        });
    }
    // Float samples stored as they are (slope 1, intercept 0: most float volumes) in
    // f32 alone: `(1.0 * x as f64 + 0.0) as f32` is `x + 0.0` for every f32 x (both
    // exact for finite x, and a zero comes out positive either way; NaN and the
    // infinities stay what they are), and the f64 round trip was the largest part of
    // reading a box (6% of a `glint batch` subject's CPU, issue 47).
    if let (Samples::F32(s), 1.0, 0.0) = (&v.samples, v.slope, v.intercept) {
        let nx = v.dims[0];
        return for_each_row(v.dims, lo, size, out, |r, start| {
            convert_row(r, s, start, lo[0], nx, |x| x + 0.0)
        });
    }
    match &v.samples {
        Samples::U8(s) => go(v, s, lo, size, out),
        Samples::I8(s) => go(v, s, lo, size, out),
        Samples::U16(s) => go(v, s, lo, size, out),
        Samples::I16(s) => go(v, s, lo, size, out),
        Samples::U32(s) => go(v, s, lo, size, out),
        Samples::I32(s) => go(v, s, lo, size, out),
        Samples::F32(s) => go(v, s, lo, size, out),
        Samples::F64(s) => go(v, s, lo, size, out),
    }
}

/// A level of an OME-Zarr store, read a box at a time through its bounded chunk cache
/// (the cache's bound is what it keeps resident).
impl Source for Stream {
    fn dims(&self) -> [usize; 3] {
        Stream::dims(self)
    }

    fn affine(&self) -> [[f64; 4]; 4] {
        Stream::affine(self)
    }

    fn resident_bytes(&self) -> u64 {
        self.cache_bound()
    }

    fn may_be_non_finite(&self) -> bool {
        // Integer types convert to finite f32 (slope 1, intercept 0), as for a
        // `Volume` read whole.
        self.is_float()
    }

    fn read(&self, lo: [isize; 3], size: [usize; 3], out: &mut [f32]) {
        self.read_box(lo, size, out)
    }

    fn problem(&self) -> Option<String> {
        Stream::problem(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn boxes_are_clamped_to_the_faces_and_scaled() {
        let v: Vec<i16> = (0..24).collect();
        let mut vol = Volume::new([4, 3, 2], [1.0; 3], Samples::I16(v)).unwrap();
        vol.slope = 2.0;
        vol.intercept = -1.0;
        let mut out = vec![0.0; 12];
        // i from -1 to 4, j = 2..4 (4 clamped to 2), k = 1.
        vol.read([-1, 2, 1], [6, 2, 1], &mut out);
        let phys = |i: usize, j: usize, k: usize| 2.0 * (i + 4 * (j + 3 * k)) as f32 - 1.0;
        let want: Vec<f32> = [0, 0, 1, 2, 3, 3]
            .iter()
            .map(|&i| phys(i, 2, 1))
            .chain([0, 0, 1, 2, 3, 3].iter().map(|&i| phys(i, 2, 1)))
            .collect();
        assert_eq!(out, want);
        assert!(!vol.may_be_non_finite());
        vol.slope = 1e36;
        assert!(vol.may_be_non_finite());
        assert_eq!(vol.resident_bytes(), 48);
    }

    /// Float samples of slope 1 and intercept 0 (read in f32 alone) come out as the
    /// f64 conversion gives them, bit for bit: negative zero as zero, NaN as NaN.
    #[test]
    fn unscaled_floats_read_as_the_f64_conversion() {
        let v = vec![
            -0.0f32,
            0.0,
            1.5e-45,
            -3.4e38,
            f32::INFINITY,
            f32::NAN,
            0.1,
            -7.25,
        ];
        let vol = Volume::new([8, 1, 1], [1.0; 3], Samples::F32(v.clone())).unwrap();
        let mut out = vec![1.0; 10];
        vol.read([-1, 0, 0], [10, 1, 1], &mut out);
        let want = |x: f32| (1.0 * x as f64 + 0.0) as f32;
        let expect: Vec<f32> = [v[0]]
            .iter()
            .chain(&v)
            .chain([&v[7]])
            .map(|&x| want(x))
            .collect();
        for (i, (a, b)) in out.iter().zip(&expect).enumerate() {
            assert!(
                a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                "{i}: {a} {b}"
            );
        }
        assert_eq!(out[1].to_bits(), 0.0f32.to_bits());
    }
}
