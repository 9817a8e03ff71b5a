//! Meshes cut by a [`Clip`] ([`Surfaces::clipped`]), and the caps that close the cut
//! solids.
//!
//! The triangles are cut against the clip's half-spaces before they are rasterised
//! (Sutherland and Hodgman, "Reentrant polygon clipping", CACM 17(1), 1974: each
//! triangle, a polygon, is cut by one plane after another, then fanned back into
//! triangles), rather than fragments being discarded per sample: the cut is exact
//! (the edge of the cut lies on the plane, not on a sample grid), it costs once per
//! clip instead of once per sample, the rasterizer's scalar and AVX2 loops and the
//! pick see the same triangles (so they agree as they do without a clip), and the
//! depth buffer never holds a hidden part. A point made on an edge is interpolated
//! from the edge's endpoints in one order (the smaller position first), so the two
//! triangles sharing an edge get the same point and the cut leaves no crack.
//!
//! Caps: where a closed mesh is cut, a line of sight through the cut meets the inside
//! of the solid, a back face, before any front face. The rasterizer draws the cut
//! plane there instead, at the depth where the ray enters the kept region and with
//! the plane's normal: the parity test of stencil capping (McReynolds and Blythe,
//! "Advanced Graphics Programming Using OpenGL", 2005, "Capping Clipped Solids"; the
//! same test, by facing alone, as three.js's `webgl_clipping_stencil` example), done
//! here on the nearest surface of each sample.

use rayon::prelude::*;

use glint_core::{Clip, HalfSpace, RenderError, Vec3};

use super::Surfaces;

/// Triangles per parallel task of a cut.
const CHUNK: usize = 1 << 14;

/// What caps a clipped [`Surfaces`] draws: the clip's half-spaces and, per triangle,
/// the sign that turns its winding out of the matter its mesh bounds, when it was cut
/// from a closed component (0 otherwise).
#[derive(Clone, Debug)]
pub(super) struct Caps {
    pub(super) planes: Vec<HalfSpace>,
    pub(super) facing: Vec<i8>,
}

impl Caps {
    /// Where the ray `o + t d` enters the kept region: the largest `t` at which it
    /// crosses a plane inwards, and the unit normal of the cap there, facing the ray
    /// (out of the cut solid); `None` when it crosses none inwards (the eye is on the
    /// kept side of every plane it looks along).
    pub(super) fn entry(&self, o: Vec3, d: Vec3) -> Option<(f64, Vec3)> {
        let (o, d) = (
            [o.x, o.y, o.z].map(f64::from),
            [d.x, d.y, d.z].map(f64::from),
        );
        let mut best: Option<(f64, [f64; 3])> = None;
        for h in &self.planes {
            let slope = dot(h.normal, d);
            if slope > 0.0 {
                let t = -h.distance(o) / slope;
                if best.is_none_or(|(b, _)| t > b) {
                    best = Some((t, h.normal));
                }
            }
        }
        best.map(|(t, n)| (t, Vec3::new(-n[0] as f32, -n[1] as f32, -n[2] as f32)))
    }
}

/// A corner of a cut polygon: an original vertex, or a point made on an edge.
#[derive(Clone, Copy, Debug)]
struct Corner {
    /// The original vertex, when it is one.
    index: Option<u32>,
    p: Vec3,
    n: Vec3,
    scalar: f32,
    color: [f32; 3],
}

/// A corner of a cut triangle: an original vertex or the `k`th new one of its chunk.
#[derive(Clone, Copy)]
enum Ref {
    Old(u32),
    New(u32),
}

/// One chunk's cut: its triangles (with the triangle each came from) and new corners.
#[derive(Default)]
struct Cut {
    triangles: Vec<([Ref; 3], u32)>,
    corners: Vec<Corner>,
}

impl Surfaces {
    /// These surfaces with every triangle cut to what `clip` keeps (triangles wholly
    /// outside dropped, those crossing a plane cut along it); with `caps`, the cut
    /// closed meshes are drawn closed by the cut planes (see the module's notes).
    /// Normals, scalars and colours of the points made on edges are interpolated
    /// (colours taken from the nearer end: labels do not blend). The camera
    /// [`Surfaces::camera`] places is unchanged (the bounding sphere is the uncut
    /// meshes'). Fails when `clip` is not valid ([`Clip::validate`]).
    ///
    /// Back faces of the cut meshes are no longer culled (they are seen through the
    /// cut); meshes the clip leaves whole keep their culling.
    pub fn clipped(&self, clip: &Clip, caps: bool) -> Result<Surfaces, RenderError> {
        clip.validate()?;
        if clip.is_empty() {
            return Ok(self.clone());
        }
        let planes = clip.half_spaces();
        let cuts: Vec<Cut> = self
            .triangles
            .par_chunks(CHUNK)
            .enumerate()
            .map(|(c, tris)| {
                let mut cut = Cut::default();
                for (k, &tri) in tris.iter().enumerate() {
                    self.cut_one(tri, (c * CHUNK + k) as u32, &planes, &mut cut);
                }
                cut
            })
            .collect();
        Ok(self.assemble(cuts, planes, caps))
    }

    /// The corner of original vertex `i`.
    fn corner(&self, i: u32) -> Corner {
        let k = i as usize;
        Corner {
            index: Some(i),
            p: self.positions[k],
            n: self.normals[k],
            scalar: self.scalars.as_ref().map_or(f32::NAN, |s| s[k]),
            color: self.colors.as_ref().map_or([f32::NAN; 3], |c| c[k]),
        }
    }

    /// Cuts triangle `id` (vertices `tri`) by `planes`, adding what is kept to `cut`.
    fn cut_one(&self, tri: [u32; 3], id: u32, planes: &[HalfSpace], cut: &mut Cut) {
        let dist = |h: &HalfSpace, p: Vec3| h.distance([p.x, p.y, p.z].map(f64::from));
        let pos = tri.map(|i| self.positions[i as usize]);
        let mut whole = true;
        for h in planes {
            let d = pos.map(|p| dist(h, p));
            if d.iter().all(|&x| x < 0.0) {
                return;
            }
            whole &= d.iter().all(|&x| x >= 0.0);
        }
        if whole {
            cut.triangles.push((tri.map(Ref::Old), id));
            return;
        }
        let mut poly: Vec<Corner> = tri.iter().map(|&i| self.corner(i)).collect();
        let mut next = Vec::with_capacity(8);
        for h in planes {
            next.clear();
            for k in 0..poly.len() {
                let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
                let (da, db) = (dist(h, a.p), dist(h, b.p));
                if da >= 0.0 {
                    next.push(a);
                }
                if (da >= 0.0) != (db >= 0.0) {
                    next.push(on_edge(a, b, da, db));
                }
            }
            std::mem::swap(&mut poly, &mut next);
            if poly.len() < 3 {
                return;
            }
        }
        let refs: Vec<Ref> = poly
            .iter()
            .map(|c| match c.index {
                Some(i) => Ref::Old(i),
                None => {
                    cut.corners.push(*c);
                    Ref::New(cut.corners.len() as u32 - 1)
                }
            })
            .collect();
        for k in 1..refs.len() - 1 {
            cut.triangles.push(([refs[0], refs[k], refs[k + 1]], id));
        }
    }

    /// The clipped surfaces from the chunks' cuts.
    fn assemble(&self, cuts: Vec<Cut>, planes: Vec<HalfSpace>, caps: bool) -> Surfaces {
        let mut out = Surfaces {
            triangles: Vec::new(),
            facing: Vec::new(),
            caps: None,
            ..self.clone()
        };
        let mut parents: Vec<u32> = Vec::new();
        for cut in cuts {
            let base = out.positions.len() as u32;
            for c in &cut.corners {
                out.positions.push(c.p);
                out.normals.push(c.n);
                if let Some(s) = &mut out.scalars {
                    s.push(c.scalar);
                }
                if let Some(s) = &mut out.colors {
                    s.push(c.color);
                }
            }
            for (tri, parent) in cut.triangles {
                out.triangles.push(tri.map(|r| match r {
                    Ref::Old(i) => i,
                    Ref::New(k) => base + k,
                }));
                parents.push(parent);
            }
        }
        // Per mesh: its first triangle, and whether the cut left it whole (then its
        // back faces may still be culled).
        let meshes = self.mesh_starts.len();
        let mut whole = vec![true; meshes];
        let mut counts = vec![0u32; meshes];
        let mut kept = vec![0u32; meshes];
        for (tri, &p) in out.triangles.iter().zip(&parents) {
            let m = self.mesh_of(p);
            counts[m] += 1;
            whole[m] &= *tri == self.triangles[p as usize];
        }
        for (m, w) in whole.iter_mut().enumerate() {
            let (t0, t1) = self.triangle_range(m);
            kept[m] = (t1 - t0) as u32;
            *w &= counts[m] == kept[m];
        }
        let mut start = 0;
        for (m, s) in out.mesh_starts.iter_mut().enumerate() {
            s.1 = start;
            start += counts[m];
        }
        out.facing = parents
            .iter()
            .map(|&p| match whole[self.mesh_of(p)] {
                true => self.facing[p as usize],
                false => 0,
            })
            .collect();
        out.caps = caps.then(|| {
            let inside = self.material_sides();
            Caps {
                planes,
                facing: parents
                    .iter()
                    .map(|&p| match self.facing[p as usize] {
                        0 => 0,
                        _ => inside[self.mesh_of(p)],
                    })
                    .collect(),
            }
        });
        out
    }

    /// Per mesh: the sign that turns the windings of its closed components out of the
    /// matter they bound, from the signed volume of all of them together (0 when it
    /// has none). One sign for the whole mesh, not one per component as culling takes
    /// (`cull::Closure::of`): a cavity, wound the other way inside a shell, bounds
    /// empty space, and a line of sight crossing it must not be capped.
    fn material_sides(&self) -> Vec<i8> {
        let mut volume = vec![0.0f64; self.mesh_starts.len()];
        let o = self.center;
        for (t, tri) in self.triangles.iter().enumerate() {
            if self.facing[t] == 0 {
                continue;
            }
            let [a, b, c] = tri.map(|i| {
                let p = self.positions[i as usize] - o;
                [p.x, p.y, p.z].map(f64::from)
            });
            let cross = [
                b[1] * c[2] - b[2] * c[1],
                b[2] * c[0] - b[0] * c[2],
                b[0] * c[1] - b[1] * c[0],
            ];
            volume[self.mesh_of(t as u32)] += dot(a, cross);
        }
        volume
            .iter()
            .map(|&v| match v {
                v if v > 0.0 => 1,
                v if v < 0.0 => -1,
                _ => 0,
            })
            .collect()
    }

    /// Triangle index range of mesh `k`.
    fn triangle_range(&self, k: usize) -> (usize, usize) {
        let start = self.mesh_starts[k].1 as usize;
        let end = self
            .mesh_starts
            .get(k + 1)
            .map_or(self.triangles.len(), |s| s.1 as usize);
        (start, end)
    }
}

/// The point where the edge from `a` (signed distance `da`) to `b` (`db`, of the other
/// sign) meets the plane, interpolated from the lexicographically smaller end so that
/// both triangles sharing the edge make the same point.
fn on_edge(a: Corner, b: Corner, da: f64, db: f64) -> Corner {
    let key = |c: &Corner| [c.p.x, c.p.y, c.p.z];
    let swap = key(&b)
        .iter()
        .zip(key(&a).iter())
        .map(|(x, y)| x.total_cmp(y))
        .find(|o| o.is_ne())
        .is_some_and(|o| o.is_lt());
    let (a, b, da, db) = if swap { (b, a, db, da) } else { (a, b, da, db) };
    let t = (da / (da - db)) as f32;
    let near = if t < 0.5 { a } else { b };
    Corner {
        index: None,
        p: a.p + (b.p - a.p) * t,
        n: (a.n + (b.n - a.n) * t).normalize_or_zero(),
        scalar: a.scalar + (b.scalar - a.scalar) * t,
        color: near.color,
    }
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
