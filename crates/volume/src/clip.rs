//! A frame's [`Clip`] in a field's index space: the ray interval it keeps, whether a
//! point is kept, and the cut faces' normals. The ray caster, the light volumes and the
//! path tracer read it; it never touches the field or the classification, so moving a
//! plane costs what moving the camera costs.

use glint_core::{Clip, Vec3};

use crate::field::Field;

/// Steps (of the frame's sample distance) within which a sample lies on a cut face:
/// the first sample past a plane is less than one step from it along its ray, so one
/// step suffices; two leave room for the pre-integrated segment that ends there.
pub(crate) const CUT_DEPTH_STEPS: f32 = 2.0;

/// One kept half-space in index space: the signed distance (mm) of index-space point
/// `p` from its boundary is `a · p + b`, positive on the kept side.
#[derive(Clone, Copy, Debug)]
struct IndexPlane {
    a: Vec3,
    b: f32,
    /// The unit world normal, into the kept side.
    normal: Vec3,
}

/// A [`Clip`] placed in a field's index space, with how its cut faces are shaded.
#[derive(Clone, Debug)]
pub(crate) struct IndexClip {
    planes: Vec<IndexPlane>,
    /// Samples closer than this (mm) to a plane lie on its cut face.
    depth: f32,
    /// Gradient magnitude (value per mm) a cut face's normal is given: twice the
    /// shader's gate, the magnitude the gate lights fully.
    strong: f32,
}

impl IndexClip {
    /// `clip` in `field`'s index space (`None` when it cuts nothing), its cut faces
    /// `depth` mm deep and given a gradient of `strong` (value per mm) where theirs is
    /// weaker. `clip` must be valid ([`Clip::validate`]).
    pub(crate) fn new(clip: &Clip, field: &Field, depth: f32, strong: f32) -> Option<IndexClip> {
        if clip.is_empty() {
            return None;
        }
        let a = &field.to_world;
        let planes = clip
            .half_spaces()
            .iter()
            .map(|h| {
                let n = h.normal;
                let coef = |j: usize| (0..3).map(|r| a[r][j] * n[r]).sum::<f64>() as f32;
                let b = (0..3).map(|r| n[r] * field.origin[r]).sum::<f64>() + h.offset;
                IndexPlane {
                    a: Vec3::new(coef(0), coef(1), coef(2)),
                    b: b as f32,
                    normal: Vec3::new(n[0] as f32, n[1] as f32, n[2] as f32),
                }
            })
            .collect();
        Some(IndexClip {
            planes,
            depth,
            strong: strong.max(1e-12),
        })
    }

    /// The part of `[t0, t1]` where the ray `o + t d` (index space, t in mm) is kept:
    /// `(a, b)` with `a > b` when none is.
    #[inline]
    pub(crate) fn interval(&self, o: Vec3, d: Vec3, (t0, t1): (f32, f32)) -> (f32, f32) {
        let (mut lo, mut hi) = (t0, t1);
        for p in &self.planes {
            let (f0, slope) = (p.a.dot(o) + p.b, p.a.dot(d));
            if slope > 0.0 {
                lo = lo.max(-f0 / slope);
            } else if slope < 0.0 {
                hi = hi.min(-f0 / slope);
            } else if f0 < 0.0 {
                return (f32::INFINITY, f32::NEG_INFINITY);
            }
        }
        (lo, hi)
    }

    /// The half-spaces as `[a.x, a.y, a.z, b, n.x, n.y, n.z, 0]` (signed distance
    /// `a · p + b` of index-space `p`, unit world normal `n`), the cut faces' depth
    /// (mm) and the strong gradient magnitude: what a device back end mirrors
    /// [`IndexClip::interval`] and [`IndexClip::cut_gradient`] with.
    pub(crate) fn device_planes(&self) -> (Vec<[f32; 8]>, f32, f32) {
        let planes = self
            .planes
            .iter()
            .map(|p| {
                let (a, n) = (p.a, p.normal);
                [a.x, a.y, a.z, p.b, n.x, n.y, n.z, 0.0]
            })
            .collect();
        (planes, self.depth, self.strong)
    }

    /// Whether a gradient `g` is weak enough for a cut face to replace it: the test
    /// [`IndexClip::cut_gradient`] makes first, which needs no position.
    #[inline]
    pub(crate) fn weak(&self, g: Vec3) -> bool {
        g.length() < self.strong
    }

    /// Whether index-space point `p` is kept.
    #[inline]
    pub(crate) fn contains(&self, p: Vec3) -> bool {
        self.planes.iter().all(|q| q.a.dot(p) + q.b >= 0.0)
    }

    /// The gradient a sample at index-space point `p` with world gradient `g` is
    /// shaded with: on a cut face (within the depth of the nearest plane) a gradient
    /// weaker than the strong magnitude is blended towards the plane's normal (which
    /// points into the kept matter, as gradients point into denser matter), so the
    /// face is lit as a surface facing out of the cut, not left flat or dark; `g`
    /// elsewhere.
    #[inline]
    pub(crate) fn cut_gradient(&self, p: Vec3, g: Vec3) -> Vec3 {
        let mut near: Option<(f32, Vec3)> = None;
        for q in &self.planes {
            let s = q.a.dot(p) + q.b;
            if s < self.depth && near.is_none_or(|(best, _)| s < best) {
                near = Some((s, q.normal));
            }
        }
        let Some((_, n)) = near else {
            return g;
        };
        let m = g.length();
        if m >= self.strong {
            return g;
        }
        // From the plane's normal at a zero gradient to `g` at the strong magnitude.
        let w = m / self.strong;
        n * (self.strong * (1.0 - w)) + g * w
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glint_core::{ClipPlane, CropBox};
    use glint_io::{Samples, Volume};

    fn field() -> Field {
        // 2 mm voxels along x, origin at (-10, 0, 5).
        let mut v = Volume::new([8, 8, 8], [2.0, 1.0, 1.0], Samples::F32(vec![0.0; 512])).unwrap();
        v.affine[0][3] = -10.0;
        v.affine[2][3] = 5.0;
        Field::new(&v).unwrap()
    }

    #[test]
    fn index_planes_measure_world_distances() {
        let f = field();
        let clip = Clip {
            planes: vec![ClipPlane {
                point: [-4.0, 0.0, 0.0],
                normal: [1.0, 0.0, 0.0],
            }],
            crop: None,
        };
        let c = IndexClip::new(&clip, &f, 1.0, 1.0).unwrap();
        // Index x = 5 is world x = 0: 4 mm inside.
        let p = Vec3::new(5.0, 3.0, 3.0);
        assert!((c.planes[0].a.dot(p) + c.planes[0].b - 4.0).abs() < 1e-5);
        assert!(c.contains(p) && !c.contains(Vec3::new(2.0, 3.0, 3.0)));
        // A ray along +x from index 0 (world -10) at 0.5 index units per mm: kept from
        // world -4, t = 6 mm.
        let (a, b) = c.interval(
            Vec3::new(0.0, 3.0, 3.0),
            Vec3::new(0.5, 0.0, 0.0),
            (0.0, 100.0),
        );
        assert!((a - 6.0).abs() < 1e-5 && b == 100.0, "{a} {b}");
        // Along -x from the same point: never kept.
        let (a, b) = c.interval(
            Vec3::new(0.0, 3.0, 3.0),
            Vec3::new(-0.5, 0.0, 0.0),
            (0.0, 100.0),
        );
        assert!(a > b);
    }

    #[test]
    fn cut_faces_take_the_planes_normal_where_the_gradient_is_weak() {
        let f = field();
        let clip = Clip {
            planes: vec![],
            crop: Some(CropBox {
                min: [-100.0, -100.0, 6.0],
                max: [100.0, 100.0, 100.0],
            }),
        };
        let c = IndexClip::new(&clip, &f, 1.0, 2.0).unwrap();
        // Index z = 1.5 is world z = 6.5: 0.5 mm above the box's floor.
        let p = Vec3::new(3.0, 3.0, 1.5);
        let g = c.cut_gradient(p, Vec3::ZERO);
        assert_eq!((g.x, g.y, g.z), (0.0, 0.0, 2.0));
        // A strong gradient is kept; far from the face too.
        let strong = Vec3::new(3.0, 0.0, 0.0);
        assert_eq!(c.cut_gradient(p, strong).x, 3.0);
        let deep = Vec3::new(3.0, 3.0, 4.0);
        assert_eq!(c.cut_gradient(deep, Vec3::ZERO).z, 0.0);
    }
}
