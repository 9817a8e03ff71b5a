//! Flying edges (Schroeder, Maynard and Geveci 2015, "Flying Edges: A
//! High-Performance Scalable Isocontouring Algorithm"; VTK's vtkFlyingEdges3D,
//! Filters/Core/vtkFlyingEdges3D.cxx): marching cubes in passes over the volume's
//! x rows, so that every vertex and triangle is written once, in parallel, at an
//! offset known in advance, without hashing, locks or a join.
//!
//! 1. Each voxel row: its crossed x edges (count, and the first and last, which trim
//!    the later passes to the part of the row where anything happens).
//! 2. Each voxel row: its crossed y edges (towards the row at `j + 1`) and z edges
//!    (towards `k + 1`), and the triangles of the row of cells it is the origin of,
//!    all within the trimmed span.
//! 3. A prefix sum over the rows (in memory order) gives each row's first vertex and
//!    first triangle.
//! 4. Each voxel row: writes its vertices (x, then y, then z edges, each in order of
//!    i) and its cells' triangles; a cell finds the vertex of each of its edges from
//!    counters of crossed edges carried along the row.
//!
//! The output depends on the volume only (not on the number of threads). Normals are
//! computed at the crossed edges only: the gradient (central differences) at the two
//! grid points, interpolated, as VTK does.

use rayon::prelude::*;

use super::table::{table, Table};
use super::Frame;

/// Stored samples: which are inside (physical value at least the iso value) and
/// their physical values.
pub(super) trait Source: Sync {
    /// The stored sample type.
    type T: Copy + Sync;
    /// Whether the sample's physical value is at least the iso value.
    fn inside(&self, x: Self::T) -> bool;
    /// The sample's physical value.
    fn value(&self, x: Self::T) -> f32;
}

/// A stored sample type that converts to f64.
pub(super) trait Raw: Copy + Sync + PartialOrd {
    /// The sample as f64 (exactly for every type here).
    fn to_f64(self) -> f64;
}

macro_rules! raw {
    ($($t:ty),*) => {$(
        impl Raw for $t {
            #[inline]
            fn to_f64(self) -> f64 {
                f64::from(self)
            }
        }
    )*};
}
raw!(u8, i8, u16, i16, u32, i32, f32);

/// Samples whose physical value `slope * x + intercept` (in f64, rounded to f32, as
/// [`glint_io::Volume::to_f32`]) grows with `x`, so that "inside" is a threshold on
/// the stored samples: `x >= lo`.
pub(super) struct Scaled<T> {
    pub slope: f64,
    pub intercept: f64,
    pub lo: T,
}

impl<T: Raw> Source for Scaled<T> {
    type T = T;
    #[inline]
    fn inside(&self, x: T) -> bool {
        x >= self.lo
    }
    #[inline]
    fn value(&self, x: T) -> f32 {
        (self.slope * x.to_f64() + self.intercept) as f32
    }
}

/// Where a row's x edges cross: `xmin` is the first crossed edge (`nx - 1` if none)
/// and `xmax` one past the last (0 if none), so grid points `0..=xmin` are in the
/// `first` state and `xmax..nx` in the `last` one.
#[derive(Clone, Copy, Default)]
struct Trim {
    xmin: u32,
    xmax: u32,
    first: bool,
    last: bool,
}

/// A voxel row's crossed x, y and z edges (its vertices) and its cells' triangles.
#[derive(Clone, Copy, Default)]
struct Counts {
    x: u32,
    y: u32,
    z: u32,
    tris: u32,
}

/// The grid points of `rows` whose edges between them may cross, or the cells of the
/// rows (spanning grid points `i` and `i + 1`) that may be cut, from the rows' trims:
/// outside this span every row keeps its first or last state, and those agree.
fn span(trims: &[Trim], nx: usize, cells: bool) -> std::ops::Range<usize> {
    let t0 = trims[0];
    let lo = if trims.iter().all(|t| t.first == t0.first) {
        trims.iter().map(|t| t.xmin).min().unwrap_or(0) as usize
    } else {
        0
    };
    let hi = if trims.iter().all(|t| t.last == t0.last) {
        trims.iter().map(|t| t.xmax).max().unwrap_or(0) as usize
    } else {
        nx - 1
    };
    // Cells: lo..hi; grid points: lo..=hi.
    let end = if cells { hi } else { hi + 1 };
    lo..end.max(lo)
}

/// The sampled volume and the frame: what every pass reads.
pub(super) struct Grid<'a, S: Source> {
    pub values: &'a [S::T],
    pub src: S,
    pub frame: &'a Frame,
}

/// The extracted mesh's arrays.
pub(super) struct Output {
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
}

/// More than `u32::MAX` vertices or triangles.
pub(super) struct TooLarge;

impl<S: Source> Grid<'_, S> {
    fn dims(&self) -> [usize; 3] {
        self.frame.dims
    }

    #[inline]
    fn row(&self, j: usize, k: usize) -> &[S::T] {
        let [nx, ny, _] = self.dims();
        &self.values[nx * (j + ny * k)..][..nx]
    }

    /// Runs the four passes.
    pub fn extract(&self) -> Result<Output, TooLarge> {
        let [_, ny, nz] = self.dims();
        let rows = ny * nz;
        // Pass 1.
        let mut trims = vec![Trim::default(); rows];
        let mut counts = vec![Counts::default(); rows];
        trims
            .par_chunks_mut(ny)
            .zip(counts.par_chunks_mut(ny))
            .enumerate()
            .for_each(|(k, (trims, counts))| {
                for (j, (t, c)) in trims.iter_mut().zip(counts.iter_mut()).enumerate() {
                    (*t, c.x) = self.trim(self.row(j, k));
                }
            });
        // Pass 2.
        let t = table();
        counts
            .par_chunks_mut(ny)
            .enumerate()
            .for_each(|(k, counts)| {
                let mut cases = Cases::new(t);
                for (j, c) in counts.iter_mut().enumerate() {
                    self.count(&trims, j, k, c, &mut cases);
                }
            });
        // Pass 3: first vertex and triangle of each row, and the totals at the end.
        let mut starts = Vec::with_capacity(rows + 1);
        let (mut v, mut tr) = (0u64, 0u64);
        for c in &counts {
            starts.push((v as u32, tr as u32));
            v += u64::from(c.x) + u64::from(c.y) + u64::from(c.z);
            tr += u64::from(c.tris);
            if v > u64::from(u32::MAX) || tr > u64::from(u32::MAX) {
                return Err(TooLarge);
            }
        }
        starts.push((v as u32, tr as u32));
        // Pass 4, a plane of rows per task, each writing its own part of the arrays.
        let mut out = Output {
            positions: vec![[0.0; 3]; v as usize],
            normals: vec![[0.0; 3]; v as usize],
            triangles: vec![[0; 3]; tr as usize],
        };
        let mut planes = Vec::with_capacity(nz);
        let (mut p, mut n, mut tri) = (
            &mut out.positions[..],
            &mut out.normals[..],
            &mut out.triangles[..],
        );
        for k in 0..nz {
            let (a, b) = (starts[k * ny], starts[(k + 1) * ny]);
            let nv = (b.0 - a.0) as usize;
            let (p0, p1) = std::mem::take(&mut p).split_at_mut(nv);
            let (n0, n1) = std::mem::take(&mut n).split_at_mut(nv);
            let (t0, t1) = std::mem::take(&mut tri).split_at_mut((b.1 - a.1) as usize);
            planes.push((k, p0, n0, t0));
            (p, n, tri) = (p1, n1, t1);
        }
        let ctx = Emit {
            table: t,
            trims: &trims,
            counts: &counts,
            starts: &starts,
        };
        planes.into_par_iter().for_each(|(k, p, n, tri)| {
            self.emit_plane(&ctx, k, p, n, tri, &mut Cases::new(t));
        });
        Ok(out)
    }

    /// Pass 1 on one row: its trim and number of crossed x edges.
    fn trim(&self, row: &[S::T]) -> (Trim, u32) {
        let s = &self.src;
        let (first, last) = (s.inside(row[0]), s.inside(row[row.len() - 1]));
        // The first grid point not in the first state ends the first crossed edge;
        // the last one not in the last state starts the last crossed edge.
        let Some(after) = find(row, false, |x| s.inside(x) != first) else {
            let none = Trim {
                xmin: row.len() as u32 - 1,
                xmax: 0,
                first,
                last,
            };
            return (none, 0);
        };
        let xmin = after - 1;
        let xmax = find(row, true, |x| s.inside(x) != last).map_or(row.len() - 1, |x| x + 1);
        let span = &row[xmin..=xmax];
        let count: u32 = span
            .iter()
            .zip(&span[1..])
            .map(|(&a, &b)| u32::from(s.inside(a) != s.inside(b)))
            .sum();
        let trim = Trim {
            xmin: xmin as u32,
            xmax: xmax as u32,
            first,
            last,
        };
        (trim, count)
    }

    /// Pass 2 on row `(j, k)`: crossed y and z edges, and the triangles of its cells
    /// (`cases` is scratch space).
    fn count(&self, trims: &[Trim], j: usize, k: usize, c: &mut Counts, cases: &mut Cases) {
        let [nx, ny, nz] = self.dims();
        let s = &self.src;
        let at = |j: usize, k: usize| trims[j + ny * k];
        let pair = |j1: usize, k1: usize| {
            let r = span(&[at(j, k), at(j1, k1)], nx, false);
            let (a, b) = (&self.row(j, k)[r.clone()], &self.row(j1, k1)[r]);
            a.iter()
                .zip(b)
                .map(|(&a, &b)| u32::from(s.inside(a) != s.inside(b)))
                .sum::<u32>()
        };
        if j + 1 < ny {
            c.y = pair(j + 1, k);
        }
        if k + 1 < nz {
            c.z = pair(j, k + 1);
        }
        if j + 1 < ny && k + 1 < nz {
            let quad = [at(j, k), at(j + 1, k), at(j, k + 1), at(j + 1, k + 1)];
            self.cases(j, k, span(&quad, nx, true), cases);
            let t = &cases.table.cases;
            c.tris = cases
                .masks
                .iter()
                .map(|&m| u32::from(t[m as usize].1))
                .sum();
        }
    }

    /// The cases of the cells `cells` of the cell row `(j, k)`, into `out.masks`
    /// (bit `c` set when corner `c` is inside; see the table).
    fn cases(&self, j: usize, k: usize, cells: std::ops::Range<usize>, out: &mut Cases) {
        out.bits.clear();
        out.masks.clear();
        if cells.is_empty() {
            return;
        }
        let s = &self.src;
        let points = cells.start..cells.end + 1;
        let [r0, r1, r2, r3] = [(j, k), (j + 1, k), (j, k + 1), (j + 1, k + 1)]
            .map(|(j, k)| &self.row(j, k)[points.clone()]);
        // Inside bits of each grid point's four rows, then each cell's left and right
        // points; plain loops over slices, which vectorise.
        out.bits.extend(
            r0.iter()
                .zip(r1)
                .zip(r2)
                .zip(r3)
                .map(|(((&a, &b), &c), &d)| {
                    u8::from(s.inside(a))
                        | u8::from(s.inside(b)) << 2
                        | u8::from(s.inside(c)) << 4
                        | u8::from(s.inside(d)) << 6
                }),
        );
        let bits = &out.bits;
        out.masks
            .extend(bits.iter().zip(&bits[1..]).map(|(&l, &r)| l | r << 1));
    }

    /// Pass 4 on plane `k`: the vertices and triangles of its rows, into its parts of
    /// the arrays.
    fn emit_plane(
        &self,
        ctx: &Emit,
        k: usize,
        mut p: &mut [[f32; 3]],
        mut n: &mut [[f32; 3]],
        mut tri: &mut [[u32; 3]],
        cases: &mut Cases,
    ) {
        let [nx, ny, nz] = self.dims();
        for j in 0..ny {
            let r = j + ny * k;
            let c = ctx.counts[r];
            let nv = (c.x + c.y + c.z) as usize;
            let (p0, p1) = std::mem::take(&mut p).split_at_mut(nv);
            let (n0, n1) = std::mem::take(&mut n).split_at_mut(nv);
            let (t0, t1) = std::mem::take(&mut tri).split_at_mut(c.tris as usize);
            (p, n, tri) = (p1, n1, t1);
            let mut slots = p0.iter_mut().zip(n0.iter_mut());
            let mut put = |point: [usize; 3], axis: usize| {
                if let Some((p, n)) = slots.next() {
                    (*p, *n) = self.edge_point(point, axis);
                }
            };
            let row = self.row(j, k);
            let tr = ctx.trims[r];
            let s = &self.src;
            for i in tr.xmin as usize..tr.xmax as usize {
                if s.inside(row[i]) != s.inside(row[i + 1]) {
                    put([i, j, k], 0);
                }
            }
            for (axis, j1, k1) in [(1, j + 1, k), (2, j, k + 1)] {
                if j1 == ny || k1 == nz {
                    continue;
                }
                let other = self.row(j1, k1);
                for i in span(&[tr, ctx.trims[j1 + ny * k1]], nx, false) {
                    if s.inside(row[i]) != s.inside(other[i]) {
                        put([i, j, k], axis);
                    }
                }
            }
            if j + 1 < ny && k + 1 < nz {
                self.emit_triangles(ctx, j, k, t0, cases);
            }
        }
    }

    /// The triangles of the cell row `(j, k)`: each cut cell's edges get their vertex
    /// from counters of the crossed edges of the four rows met so far.
    fn emit_triangles(
        &self,
        ctx: &Emit,
        j: usize,
        k: usize,
        out: &mut [[u32; 3]],
        cases: &mut Cases,
    ) {
        let [nx, ny, _] = self.dims();
        let row = |j: usize, k: usize| j + ny * k;
        let rx = [row(j, k), row(j + 1, k), row(j, k + 1), row(j + 1, k + 1)];
        let first = |r: usize| ctx.starts[r].0;
        // Vertex of the next crossed x edge of each row (cell edges 0..4), y edge of
        // rows (j, k) and (j, k + 1) (cell edges 4..8), z edge of rows (j, k) and
        // (j + 1, k) (cell edges 8..12).
        let mut cx = rx.map(first);
        let mut cy = [rx[0], rx[2]].map(|r| first(r) + ctx.counts[r].x);
        let mut cz = [rx[0], rx[1]].map(|r| first(r) + ctx.counts[r].x + ctx.counts[r].y);
        let cells = span(&rx.map(|r| ctx.trims[r]), nx, true);
        let mut slots = out.iter_mut();
        let flip = self.frame.flip;
        self.cases(j, k, cells, cases);
        for &mask in &cases.masks {
            if mask == 0 || mask == 255 {
                continue;
            }
            let m = u32::from(mask);
            let cut = |a: u32, b: u32| (m >> a ^ m >> b) & 1;
            // Crossed y edges at the cell's left corners (z = 0, 1), z edges (y = 0, 1).
            let (y0, y1) = (cut(0, 2), cut(4, 6));
            let (z0, z1) = (cut(0, 4), cut(2, 6));
            let ids = [
                cx[0],
                cx[1],
                cx[2],
                cx[3],
                cy[0],
                cy[0] + y0,
                cy[1],
                cy[1] + y1,
                cz[0],
                cz[0] + z0,
                cz[1],
                cz[1] + z1,
            ];
            let (start, count) = ctx.table.cases[mask as usize];
            for t in &ctx.table.triangles[start as usize..][..count as usize] {
                let mut v = t.map(|e| ids[e as usize]);
                if flip {
                    v.swap(1, 2);
                }
                if let Some(slot) = slots.next() {
                    *slot = v;
                }
            }
            for (e, c) in cx.iter_mut().enumerate() {
                *c += cut(2 * e as u32, 2 * e as u32 + 1);
            }
            cy[0] += y0;
            cy[1] += y1;
            cz[0] += z0;
            cz[1] += z1;
        }
    }

    #[inline]
    fn at(&self, p: [usize; 3]) -> f32 {
        let [nx, ny, _] = self.dims();
        self.src.value(self.values[p[0] + nx * (p[1] + ny * p[2])])
    }

    /// Position and unit normal where the iso value crosses the edge from grid point
    /// `p` along `axis`.
    fn edge_point(&self, p: [usize; 3], axis: usize) -> ([f32; 3], [f32; 3]) {
        let f = self.frame;
        let mut q = p;
        q[axis] += 1;
        let (a, b) = (self.at(p), self.at(q));
        let t = (f.iso - a) / (b - a);
        let t = if t.is_finite() {
            t.clamp(0.0, 1.0)
        } else {
            0.5
        };
        let mut idx = p.map(|x| x as f64);
        idx[axis] += f64::from(t);
        let pos = [0, 1, 2].map(|r| {
            let row = &f.affine[r];
            (row[0] * idx[0] + row[1] * idx[1] + row[2] * idx[2] + row[3]) as f32
        });
        let (ga, gb) = (self.gradient(p), self.gradient(q));
        let g = [0, 1, 2].map(|d| ga[d] + t * (gb[d] - ga[d]));
        let m = &f.grad_to_world;
        let w = [0, 1, 2].map(|r| -(m[r][0] * g[0] + m[r][1] * g[1] + m[r][2] * g[2]));
        let len = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
        let normal = if len > 0.0 && len.is_finite() {
            w.map(|x| x / len)
        } else {
            [0.0; 3]
        };
        (pos, normal)
    }

    /// Index-space gradient at grid point `p`: central differences, one-sided at the
    /// border.
    #[inline]
    fn gradient(&self, p: [usize; 3]) -> [f32; 3] {
        let [nx, ny, nz] = self.dims();
        let inner = (1..nx - 1).contains(&p[0])
            && (1..ny - 1).contains(&p[1])
            && (1..nz - 1).contains(&p[2]);
        if inner {
            // The common case, without the border's clamping: neighbours at fixed
            // strides. `(b - a) * 0.5` equals the border path's `(b - a) / 2.0`.
            let at = p[0] + nx * (p[1] + ny * p[2]);
            let v = |i: usize| self.src.value(self.values[i]);
            let d = |s: usize| (v(at + s) - v(at - s)) * 0.5;
            return [d(1), d(nx), d(nx * ny)];
        }
        let dims = [nx, ny, nz];
        let along = |d: usize| {
            let (mut lo, mut hi) = (p, p);
            lo[d] = p[d].saturating_sub(1);
            hi[d] = (p[d] + 1).min(dims[d] - 1);
            let span = (hi[d] - lo[d]) as f32;
            (self.at(hi) - self.at(lo)) / span
        };
        [along(0), along(1), along(2)]
    }
}

/// A task's scratch space for the cases of a row of cells.
struct Cases {
    table: &'static Table,
    /// Per grid point, the inside bits of its four rows (corner bits 0, 2, 4, 6).
    bits: Vec<u8>,
    /// Per cell, its case.
    masks: Vec<u8>,
}

impl Cases {
    fn new(table: &'static Table) -> Cases {
        Cases {
            table,
            bits: Vec::new(),
            masks: Vec::new(),
        }
    }
}

/// The index of the first (or, if `last`, the last) element of `row` for which `f`
/// holds. Chunks are tested whole first (a loop without early exit, which
/// vectorises), then the chunk that holds one is searched.
fn find<T: Copy>(row: &[T], last: bool, f: impl Fn(T) -> bool) -> Option<usize> {
    const CHUNK: usize = 32;
    let any = |c: &[T]| c.iter().fold(false, |a, &x| a | f(x));
    if last {
        let mut end = row.len();
        for c in row.rchunks(CHUNK) {
            end -= c.len();
            if any(c) {
                return c.iter().rposition(|&x| f(x)).map(|i| end + i);
            }
        }
    } else {
        let mut start = 0;
        for c in row.chunks(CHUNK) {
            if any(c) {
                return c.iter().position(|&x| f(x)).map(|i| start + i);
            }
            start += c.len();
        }
    }
    None
}

/// What pass 4 reads: the case table and passes 1 to 3's results.
struct Emit<'a> {
    table: &'static Table,
    trims: &'a [Trim],
    counts: &'a [Counts],
    starts: &'a [(u32, u32)],
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use glint_io::{Mesh, Samples, Volume};

    use super::super::extract;
    use super::super::table::{table, EDGES};

    /// A `dims` volume of pseudo-random bytes (xorshift), which meets every case of
    /// the table, ambiguous ones included: inside a border of zeros (a closed surface)
    /// if `border`; constant along x if `flat` (rows without crossed x edges, whose
    /// y and z edges all cross or none).
    fn noise(dims: [usize; 3], seed: u64, border: bool, flat: bool) -> Volume {
        let mut x = seed;
        let mut v = Vec::with_capacity(dims.iter().product());
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    if !flat || i == 0 {
                        x ^= x << 13;
                        x ^= x >> 7;
                        x ^= x << 17;
                    }
                    let on_border = [i, j, k]
                        .iter()
                        .zip(&dims)
                        .any(|(&p, &d)| p == 0 || p == d - 1);
                    v.push(if border && on_border {
                        0
                    } else {
                        (x >> 56) as u8
                    });
                }
            }
        }
        Volume::new(dims, [1.0; 3], Samples::U8(v)).unwrap()
    }

    /// The grid edge (lower grid point, axis) a vertex of an identity-affine mesh
    /// lies strictly inside.
    fn edge_of(p: [f32; 3]) -> ([i64; 3], usize) {
        let axis = (0..3)
            .find(|&a| p[a].fract() != 0.0)
            .expect("vertex inside an edge");
        (p.map(|x| x.floor() as i64), axis)
    }

    /// Rotates a triangle so its smallest element comes first (same orientation).
    fn canonical<T: Ord + Copy>(t: [T; 3]) -> [T; 3] {
        let m = (0..3).min_by_key(|&i| t[i]).unwrap_or(0);
        [t[m], t[(m + 1) % 3], t[(m + 2) % 3]]
    }

    /// Marching cubes cell by cell with the table, triangles as grid edges.
    fn reference(vol: &Volume, iso: f32) -> Vec<[([i64; 3], usize); 3]> {
        let [nx, ny, nz] = vol.dims;
        let v = vol.to_f32();
        let inside = |i: usize, j: usize, k: usize| v[i + nx * (j + ny * k)] >= iso;
        let t = table();
        let mut out = Vec::new();
        for k in 0..nz - 1 {
            for j in 0..ny - 1 {
                for i in 0..nx - 1 {
                    let mask = (0..8).fold(0usize, |m, c| {
                        let b = inside(i + (c & 1), j + (c >> 1 & 1), k + (c >> 2 & 1));
                        m | usize::from(b) << c
                    });
                    let (start, count) = t.cases[mask];
                    for tri in &t.triangles[start as usize..][..count as usize] {
                        out.push(canonical(tri.map(|e| {
                            let (c, _) = EDGES[e as usize];
                            let p = [i, j, k].map(|x| x as i64);
                            let p = [
                                p[0] + i64::from(c & 1),
                                p[1] + i64::from(c >> 1 & 1),
                                p[2] + i64::from(c >> 2 & 1),
                            ];
                            (p, e as usize / 4)
                        })));
                    }
                }
            }
        }
        out.sort();
        out
    }

    fn edges_used_twice(mesh: &Mesh) -> bool {
        let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
        for t in &mesh.triangles {
            for k in 0..3 {
                *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        directed
            .iter()
            .all(|(&(a, b), &n)| n == 1 && directed.get(&(b, a)) == Some(&1))
    }

    #[test]
    fn noise_gives_the_cell_by_cell_triangles_with_one_vertex_per_edge() {
        let cases = [
            ([9, 7, 6], 1, true, false),
            ([23, 18, 15], 2, true, false),
            ([3, 40, 4], 3, true, false),
            ([21, 16, 13], 6, false, false),
            ([2, 9, 30], 7, false, false),
            ([19, 14, 11], 8, false, true),
            ([18, 14, 11], 9, true, true),
        ];
        for (dims, seed, border, flat) in cases {
            let vol = noise(dims, seed, border, flat);
            let mesh = extract(&vol, 127.5).unwrap();
            assert!(!mesh.triangles.is_empty());
            let edges: Vec<_> = mesh.positions.iter().map(|&p| edge_of(p)).collect();
            let mut distinct = edges.clone();
            distinct.sort();
            distinct.dedup();
            assert_eq!(
                distinct.len(),
                edges.len(),
                "{dims:?}: a grid edge has two vertices"
            );
            let mut got: Vec<_> = mesh
                .triangles
                .iter()
                .map(|t| canonical(t.map(|v| edges[v as usize])))
                .collect();
            got.sort();
            assert_eq!(got, reference(&vol, 127.5), "{dims:?}");
            // Every vertex is used (the counts matched the vertices written).
            let mut used = vec![false; mesh.positions.len()];
            mesh.triangles
                .iter()
                .flatten()
                .for_each(|&v| used[v as usize] = true);
            assert!(used.iter().all(|&u| u), "{dims:?}");
            // Inside a border of outside samples the surface is closed.
            assert!(!border || edges_used_twice(&mesh), "{dims:?}");
        }
    }

    #[test]
    fn the_mesh_does_not_depend_on_the_number_of_threads() {
        let vol = noise([31, 26, 20], 4, false, false);
        let with = |n: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap();
            pool.install(|| extract(&vol, 100.0).unwrap())
        };
        let one = with(1);
        assert!(!one.triangles.is_empty());
        assert_eq!(one, with(3));
        assert_eq!(one, with(8));
    }

    #[test]
    fn stored_integers_give_the_mesh_of_their_physical_values() {
        let base = noise([17, 15, 12], 5, true, false);
        let Samples::U8(bytes) = &base.samples else {
            unreachable!()
        };
        let as_f32 = |vol: &Volume| {
            let mut f = Volume::new(vol.dims, [1.0; 3], Samples::F32(vol.to_f32())).unwrap();
            f.affine = vol.affine;
            f
        };
        let cases: Vec<(Samples, f64, f64, f32)> = vec![
            (Samples::U8(bytes.clone()), 1.0, 0.0, 128.0),
            (Samples::U8(bytes.clone()), 0.37, -3.0, 20.1),
            (
                Samples::I16(bytes.iter().map(|&b| i16::from(b) * 100 - 9000).collect()),
                0.5,
                7.0,
                -1234.5,
            ),
            (
                Samples::U16(bytes.iter().map(|&b| u16::from(b) * 250).collect()),
                2.5e-3,
                0.0,
                40.0,
            ),
            (
                Samples::I32(bytes.iter().map(|&b| i32::from(b) - 128).collect()),
                1.0,
                0.0,
                0.0,
            ),
            // A negative slope: read through f32.
            (
                Samples::I8(bytes.iter().map(|&b| (b / 2) as i8).collect()),
                -1.0,
                0.0,
                -30.0,
            ),
        ];
        for (samples, slope, intercept, iso) in cases {
            let mut vol = Volume::new(base.dims, [1.0; 3], samples).unwrap();
            (vol.slope, vol.intercept) = (slope, intercept);
            let mesh = extract(&vol, iso).unwrap();
            assert!(!mesh.triangles.is_empty(), "slope {slope} iso {iso}");
            assert_eq!(
                mesh,
                extract(&as_f32(&vol), iso).unwrap(),
                "slope {slope} iso {iso}"
            );
        }
        // Beyond the samples' range: nothing inside, or everything.
        assert!(extract(&base, 300.0).unwrap().triangles.is_empty());
        assert!(extract(&base, -1.0).unwrap().triangles.is_empty());
    }
}
