//! Picking a surface: the nearest triangle one ray meets ([`Surfaces::pick`]).
//!
//! One ray is tested against every triangle (Möller and Trumbore, "Fast, minimum
//! storage ray/triangle intersection", 1997), in parallel chunks. Hand-written rather
//! than taken from a BVH crate (`bvh`, `parry3d`): building any acceleration
//! structure visits every triangle once and costs more than the one ray's linear
//! scan it would save; the test itself is a dozen lines.

use rayon::prelude::*;

use glint_core::Vec3;

use crate::Surfaces;

/// Triangles per parallel task of a pick (below it one thread scans them all).
const PICK_CHUNK: usize = 1 << 16;

/// Where a ray meets the nearest surface ([`Surfaces::pick`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    /// Ray parameter of the hit: mm along the unit direction from the origin.
    pub t: f32,
    /// The point, world mm.
    pub point: Vec3,
    /// Which mesh (in the order given to [`Surfaces::new`]).
    pub mesh: usize,
    /// Which triangle, counted over all meshes.
    pub triangle: u32,
}

impl Surfaces {
    /// The nearest triangle the ray `origin + t dir` (`dir` a unit vector) meets at
    /// `t > 0`, front or back face; `None` when it meets none. On surfaces cut by
    /// [`Surfaces::clipped`] only what the clip keeps is met; with caps, a ray that
    /// meets the inside of a cut closed mesh first is stopped by the cap (the point
    /// where it enters the kept region; the triangle named is the one behind it).
    pub fn pick(&self, origin: Vec3, dir: Vec3) -> Option<SurfaceHit> {
        let nearest = |a: Option<(f32, u32)>, b: Option<(f32, u32)>| match (a, b) {
            (Some(x), Some(y)) => Some(if y.0 < x.0 { y } else { x }),
            (x, y) => x.or(y),
        };
        let (t, triangle) = self
            .triangles
            .par_chunks(PICK_CHUNK)
            .enumerate()
            .map(|(c, chunk)| {
                let mut best: Option<(f32, u32)> = None;
                for (i, tri) in chunk.iter().enumerate() {
                    let [a, b, c2] = tri.map(|v| self.positions[v as usize]);
                    if let Some(t) = intersect(origin, dir, a, b, c2) {
                        if best.is_none_or(|(bt, _)| t < bt) {
                            best = Some((t, (c * PICK_CHUNK + i) as u32));
                        }
                    }
                }
                best
            })
            .reduce(|| None, nearest)?;
        let t = self.capped(origin, dir, t, triangle);
        Some(SurfaceHit {
            t,
            point: origin + dir * t,
            mesh: self.mesh_of(triangle),
            triangle,
        })
    }
}

impl Surfaces {
    /// The ray parameter of a pick that met triangle `id` at `t`: the cap's in front
    /// of it when the triangle shows the inside of a capped cut mesh, else `t`.
    fn capped(&self, origin: Vec3, dir: Vec3, t: f32, id: u32) -> f32 {
        let Some(caps) = &self.caps else {
            return t;
        };
        let o = caps.facing[id as usize];
        let [a, b, c] = self.triangles[id as usize].map(|i| self.positions[i as usize]);
        let out = (b - a).cross(c - a) * f32::from(o);
        if o == 0 || out.dot(dir) <= 0.0 {
            return t;
        }
        match caps.entry(origin, dir) {
            Some((e, _)) if e > 0.0 && (e as f32) < t => e as f32,
            _ => t,
        }
    }
}

/// The parameter `t > 0` at which the ray `o + t d` meets triangle `(a, b, c)`, either
/// side (Möller-Trumbore); `None` when it misses or runs parallel to it.
fn intersect(o: Vec3, d: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Option<f32> {
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() <= f32::EPSILON * e1.length() * e2.length() {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - a;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > 0.0).then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glint_io::Mesh;

    /// Two unit squares facing +z at z = 0 and z = -2, as separate meshes.
    fn two_squares() -> Surfaces {
        let square = |z: f32| Mesh {
            positions: vec![
                [-1.0, -1.0, z],
                [1.0, -1.0, z],
                [1.0, 1.0, z],
                [-1.0, 1.0, z],
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            normals: None,
            scalars: None,
        };
        Surfaces::new([&square(0.0), &square(-2.0)]).unwrap()
    }

    #[test]
    fn the_nearest_triangle_is_picked_from_either_side() {
        let s = two_squares();
        let down = Vec3::new(0.0, 0.0, -1.0);
        let hit = s.pick(Vec3::new(0.3, -0.2, 5.0), down).unwrap();
        assert!((hit.t - 5.0).abs() < 1e-5, "{hit:?}");
        assert_eq!(hit.mesh, 0);
        assert!((hit.point.z).abs() < 1e-5);
        // From below, the other square is nearer.
        let hit = s.pick(Vec3::new(0.3, -0.2, -5.0), -down).unwrap();
        assert!((hit.t - 3.0).abs() < 1e-5, "{hit:?}");
        assert_eq!(hit.mesh, 1);
        assert!(hit.triangle >= 2);
        // Between the two looking down: the lower one.
        let hit = s.pick(Vec3::new(0.0, 0.5, -1.0), down).unwrap();
        assert_eq!(hit.mesh, 1);
    }

    #[test]
    fn misses_and_hits_behind_the_origin_give_nothing() {
        let s = two_squares();
        let down = Vec3::new(0.0, 0.0, -1.0);
        assert_eq!(s.pick(Vec3::new(1.5, 0.0, 5.0), down), None);
        assert_eq!(s.pick(Vec3::new(0.0, 0.0, -3.0), down), None);
        // Parallel to the squares.
        assert_eq!(
            s.pick(Vec3::new(-5.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0)),
            None
        );
    }
}
