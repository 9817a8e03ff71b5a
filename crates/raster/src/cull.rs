//! Back-face culling of closed meshes.
//!
//! Seen from outside, the nearest surface along any ray through a closed, consistently
//! oriented surface is one the ray enters it through: a triangle facing the eye. The
//! triangles facing away can then be left out of the z-buffer without changing what it
//! keeps (up to ties and rounding where a back face meets a front face, on the
//! silhouette). The topology is examined once per mesh ([`Closure::of`]); each frame
//! decides per mesh whether the eye may see a back face ([`cull_signs`]).
//!
//! A surface with holes whose rims are planar, and which lies wholly on one side of
//! each rim's plane, is as good as closed for an eye on that side of every plane: the
//! flat caps that would close it face away from such an eye, so no line of sight
//! enters the surface through a hole before it meets a front face. The isosurface of
//! a volume is such a surface where it is cut by the volume's boundary (the MNI152
//! template's brain stem, with the default prefilter, at iso 60).

use glint_core::camera::{Camera, Projection};
use glint_core::Vec3;

/// Holes a mesh may have and still be culled (each costs a pass over its vertices).
const MAX_CAPS: usize = 64;

/// What culling needs to know of a mesh besides its triangles' orientations, found
/// once ([`Closure::of`]).
#[derive(Clone, Debug)]
pub(super) struct Closure {
    /// The mesh's bounding box, `[lo, hi]`.
    pub(super) bounds: [Vec3; 2],
    /// The flat caps that close its holes.
    pub(super) caps: Vec<Cap>,
}

/// The flat polygon that closes a planar hole of a mesh lying on one side of it.
#[derive(Clone, Copy, Debug)]
pub(super) struct Cap {
    /// A point of its plane.
    pub(super) point: Vec3,
    /// Unit normal pointing out of what the capped component encloses (away from
    /// the mesh).
    pub(super) normal: Vec3,
}

type P = [f64; 3];

fn sub(a: P, b: P) -> P {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: P, b: P) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: P, b: P) -> P {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Per component: whether it is open, six times its signed volume (with its caps)
/// and the sum of the terms' magnitudes (its scale).
#[derive(Clone, Copy, Default)]
struct Part {
    open: bool,
    volume: f64,
    scale: f64,
}

impl Part {
    fn add(&mut self, a: P, b: P, c: P) {
        let det = dot(a, cross(b, c));
        self.volume += det;
        self.scale += det.abs();
    }
}

impl Closure {
    /// Examines the mesh of `positions` and `triangles` (indices in range). Returns,
    /// per triangle, `1` when it belongs to a component (edge-connected) that is
    /// closed (every edge in exactly two of its triangles, once each way) or capped
    /// ([`Cap`]) and encloses a positive signed volume (its windings' normals point
    /// out of what it encloses), `-1` when that volume is negative (they point in),
    /// `0` when its component is neither (a border that is not a planar rim with the
    /// mesh behind it, a non-manifold edge, neighbours wound differently) or flat;
    /// and the mesh's closure. Taken per component, a cavity (a component inside
    /// another, wound the other way) and a component the file winds the other way
    /// both get the sign that turns their own winding out of what they enclose;
    /// either is right for culling, as a cavity is hidden from an eye outside the
    /// component around it anyway.
    pub(super) fn of(positions: &[Vec3], triangles: &[[u32; 3]]) -> (Vec<i8>, Closure) {
        let n = triangles.len();
        let bounds = super::bounding_box(positions);
        let none = || {
            let closure = Closure {
                bounds,
                caps: Vec::new(),
            };
            (vec![0; n], closure)
        };
        // Triangles are indexed by u32 in the edge lists and the disjoint sets.
        if n == 0 || n >= u32::MAX as usize {
            return none();
        }
        // About the centroid, in f64, for the volumes' precision.
        let origin = centroid(positions);
        let at = |i: u32| {
            let p = positions[i as usize];
            sub([p.x, p.y, p.z].map(f64::from), origin)
        };
        let mut open = vec![false; n];
        let (mut sets, border) = neighbours(positions.len(), triangles, &mut open);
        let mut parts = vec![Part::default(); n];
        for (t, tri) in triangles.iter().enumerate() {
            let part = &mut parts[sets.find(t as u32) as usize];
            part.open |= open[t];
            let [a, b, c] = tri.map(at);
            part.add(a, b, c);
        }
        let loops = rims(&border);
        if loops.len() > MAX_CAPS {
            return none();
        }
        let diagonal = f64::from((bounds[1] - bounds[0]).length());
        let mut caps = Vec::new();
        for rim in loops {
            let roots: Vec<u32> = rim.triangles.iter().map(|&t| sets.find(t)).collect();
            let one = roots.iter().all(|&r| r == roots[0]);
            match (rim.simple && one)
                .then(|| cap(&rim.vertices, &at, diagonal))
                .flatten()
            {
                Some((point, normal, volume)) => {
                    let part = &mut parts[roots[0] as usize];
                    part.volume += volume.volume;
                    part.scale += volume.scale;
                    caps.push((roots[0], point, normal));
                }
                None => roots.iter().for_each(|&r| parts[r as usize].open = true),
            }
        }
        // Each cap's plane must have the whole mesh (its triangles) behind it, as its
        // component's orientation turns the cap's normal out.
        let mut outward = Vec::new();
        for (root, point, normal) in caps {
            let part = &mut parts[root as usize];
            let o = f64::from(part.orientation());
            let normal = normal.map(|x| o * x);
            let tol = 1e-5 * diagonal;
            let behind = |i: &u32| dot(sub(at(*i), point), normal) <= tol;
            if o != 0.0 && triangles.iter().flatten().all(behind) {
                outward.push((root, point, normal));
            } else {
                part.open = true;
            }
        }
        let facing: Vec<i8> = (0..n as u32)
            .map(|t| parts[sets.find(t) as usize].orientation())
            .collect();
        let caps = outward
            .into_iter()
            .filter(|&(root, ..)| parts[root as usize].orientation() != 0)
            .map(|(_, point, normal)| {
                let p = [0, 1, 2].map(|k| point[k] + origin[k]);
                let f = |v: P| Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32);
                Cap {
                    point: f(p),
                    normal: f(normal),
                }
            })
            .collect();
        (facing, Closure { bounds, caps })
    }
}

impl Part {
    /// The component's orientation, 0 when open or (nearly) flat, like a sheet glued
    /// to its own reverse.
    fn orientation(&self) -> i8 {
        let enclosing = self.volume.abs() > 1e-6 * self.scale;
        if self.open || !enclosing {
            0
        } else if self.volume > 0.0 {
            1
        } else {
            -1
        }
    }
}

/// Joins triangles that share an edge, used once each way, into components; marks
/// `open` the triangles of non-manifold edges, of edges two neighbours use the same
/// way and of repeated indices. Returns the components and the border edges (used
/// once), directed as their triangle winds them, with the triangle. The edges are
/// found through each vertex's outgoing edges (a few a vertex), not by sorting them.
fn neighbours(
    vertices: usize,
    triangles: &[[u32; 3]],
    open: &mut [bool],
) -> (DisjointSets, Vec<(u32, u32, u32)>) {
    let directed = |tri: &[u32; 3]| [0, 1, 2].map(|k| (tri[k], tri[(k + 1) % 3]));
    // Per vertex, its outgoing edges (head, triangle), in compressed rows.
    let mut start = vec![0u32; vertices + 1];
    for tri in triangles {
        for &i in tri {
            start[i as usize + 1] += 1;
        }
    }
    for v in 0..vertices {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut out = vec![(0u32, 0u32); 3 * triangles.len()];
    for (t, tri) in triangles.iter().enumerate() {
        for (a, b) in directed(tri) {
            out[fill[a as usize] as usize] = (b, t as u32);
            fill[a as usize] += 1;
        }
    }
    let from = |a: u32| &out[start[a as usize] as usize..start[a as usize + 1] as usize];
    let mut sets = DisjointSets::new(triangles.len());
    let mut border = Vec::new();
    for (t, tri) in triangles.iter().enumerate() {
        for (a, b) in directed(tri) {
            let same = from(a).iter().filter(|e| e.0 == b).count();
            let mut back = from(b).iter().filter(|e| e.0 == a);
            match (a != b && same == 1, back.next(), back.next()) {
                // Used twice, once each way: the two triangles are neighbours that agree.
                (true, Some(&(_, u)), None) => sets.union(t as u32, u),
                // Used once: a border.
                (true, None, _) => border.push((a, b, t as u32)),
                // A repeated index, a non-manifold edge or neighbours that disagree.
                _ => open[t] = true,
            }
        }
    }
    (sets, border)
}

/// A loop of border edges: its vertices in order, the triangles of its edges, and
/// whether it is simple (each vertex left by one border edge, the chain closing).
struct Rim {
    vertices: Vec<u32>,
    triangles: Vec<u32>,
    simple: bool,
}

/// The border's edges `(from, to, triangle)` chained into loops.
fn rims(border: &[(u32, u32, u32)]) -> Vec<Rim> {
    let mut by_start = border.to_vec();
    by_start.sort_unstable();
    let mut used = vec![false; by_start.len()];
    let mut rims = Vec::new();
    for first in 0..by_start.len() {
        if used[first] {
            continue;
        }
        let (mut vertices, mut triangles) = (Vec::new(), Vec::new());
        let mut k = first;
        let simple = loop {
            used[k] = true;
            let (from, to, t) = by_start[k];
            vertices.push(from);
            triangles.push(t);
            if to == by_start[first].0 {
                break vertices.len() >= 3;
            }
            // The one border edge leaving `to`; two would be a vertex where the
            // surface is pinched, none a chain that does not close.
            let lo = by_start.partition_point(|e| e.0 < to);
            let hi = by_start.partition_point(|e| e.0 <= to);
            if hi != lo + 1 || used[lo] {
                break false;
            }
            k = lo;
        };
        rims.push(Rim {
            vertices,
            triangles,
            simple,
        });
    }
    rims
}

/// The cap of the rim through `vertices` (at `at`, of a mesh `diagonal` across): a
/// point of its plane, its unit normal as the surface's winding orients it, and the
/// volume it adds to its component; `None` when the rim is not planar.
fn cap(vertices: &[u32], at: &impl Fn(u32) -> P, diagonal: f64) -> Option<(P, P, Part)> {
    let ps: Vec<P> = vertices.iter().map(|&i| at(i)).collect();
    let mut c = [0.0; 3];
    for p in &ps {
        c = [c[0] + p[0], c[1] + p[1], c[2] + p[2]];
    }
    let c = c.map(|x| x / ps.len() as f64);
    // The cap runs against the rim (the surface uses each rim edge one way, the cap
    // the other), so its vector area is minus the rim's (Newell's).
    let mut area = [0.0; 3];
    let mut cap_part = Part::default();
    for (k, &p) in ps.iter().enumerate() {
        let q = ps[(k + 1) % ps.len()];
        area = sub(area, cross(sub(p, c), sub(q, c)));
        cap_part.add(c, q, p);
    }
    let len = dot(area, area).sqrt();
    let nonzero = len > 0.0;
    if !nonzero {
        return None;
    }
    let normal = area.map(|x| x / len);
    let tol = 1e-5 * diagonal;
    if !ps.iter().all(|&p| dot(sub(p, c), normal).abs() <= tol) {
        return None;
    }
    Some((c, normal, cap_part))
}

fn centroid(positions: &[Vec3]) -> P {
    let mut sum = [0.0f64; 3];
    for p in positions {
        sum[0] += f64::from(p.x);
        sum[1] += f64::from(p.y);
        sum[2] += f64::from(p.z);
    }
    let n = positions.len().max(1) as f64;
    sum.map(|s| s / n)
}

/// Union-find over triangle indices (path halving, union by index).
struct DisjointSets {
    parent: Vec<u32>,
}

impl DisjointSets {
    fn new(n: usize) -> DisjointSets {
        DisjointSets {
            parent: (0..n as u32).collect(),
        }
    }

    fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let up = self.parent[self.parent[x as usize] as usize];
            self.parent[x as usize] = up;
            x = up;
        }
        x
    }

    fn union(&mut self, a: u32, b: u32) {
        let (a, b) = (self.find(a), self.find(b));
        if a != b {
            self.parent[a.max(b) as usize] = a.min(b);
        }
    }
}

/// For a frame seen by `camera`, per mesh: the factor that, times a triangle's
/// orientation ([`Closure::of`]) and its doubled signed area on the sample grid of
/// image plane `plane`, is positive exactly when the triangle faces away from the eye;
/// 0 where the mesh is not to be culled.
///
/// Perspective: only meshes wholly beyond `near` in front of the eye (all eight
/// corners of the bounding box), so that no triangle of it is dropped at the near
/// plane and the eye is outside every solid it encloses, with the eye at least `near`
/// behind each cap's plane. Orthographic: every mesh whose caps face away from the
/// view (the rasterizer keeps every triangle, whatever its depth, so each line of
/// sight meets a closed surface first where it enters it).
pub(super) fn cull_signs(
    camera: &Camera,
    plane: [f32; 4],
    near: f32,
    closures: &[Closure],
) -> Vec<f32> {
    // With c = (right, up, forward) . (p - eye), a triangle's outward normal n faces
    // away from the eye when n . (a - eye) = det(a - eye, b - eye, c - eye) > 0
    // (perspective; n . forward > 0 orthographic). That determinant is det(R) times
    // that of the camera-space vertices, which is the product of the (positive)
    // depths times the doubled area in (u, v) = (cx, cy) / cz, which is du dv times
    // the area on the sample grid (x = (u - u0) / du, y = (v - v0) / dv). The
    // orthographic case gives the same factor with the depths left out.
    let [_, du, _, dv] = plane;
    let det = camera.right.dot(camera.up.cross(camera.forward));
    let flip = det * du * dv;
    let flip = if flip > 0.0 {
        1.0
    } else if flip < 0.0 {
        -1.0
    } else {
        // Degenerate or NaN camera: no culling.
        return vec![0.0; closures.len()];
    };
    let perspective = camera.projection == Projection::Perspective;
    closures
        .iter()
        .map(|m| {
            let [lo, hi] = m.bounds;
            let ahead = !perspective
                || (0..8).all(|k| {
                    let corner = Vec3::new(
                        if k & 1 == 0 { lo.x } else { hi.x },
                        if k & 2 == 0 { lo.y } else { hi.y },
                        if k & 4 == 0 { lo.z } else { hi.z },
                    );
                    (corner - camera.eye).dot(camera.forward) > near
                });
            let behind_caps = m.caps.iter().all(|c| {
                if perspective {
                    (c.point - camera.eye).dot(c.normal) > near
                } else {
                    camera.forward.dot(c.normal) > 1e-6
                }
            });
            if ahead && behind_caps {
                flip
            } else {
                0.0
            }
        })
        .collect()
}
