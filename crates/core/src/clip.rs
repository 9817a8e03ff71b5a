//! Clip planes and a crop box: the part of world space a render keeps.
//!
//! Each [`ClipPlane`] keeps the half-space its normal points into; a [`CropBox`] keeps
//! its inside (six such half-spaces). What a [`Clip`] keeps is the intersection of
//! all of them: a convex region, so every ray crosses it in one interval, which the
//! ray caster and the light transport cut their rays to (a cut costs a few
//! multiplications per ray and nothing per sample; the classification is unchanged).

use serde::{Deserialize, Serialize};

use crate::error::RenderError;

/// A plane through `point` (world mm) with normal `normal` (world, any length but
/// zero): the render keeps the side the normal points to.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClipPlane {
    /// A point of the plane, world mm.
    pub point: [f64; 3],
    /// The normal, towards the kept side (normalised when used).
    pub normal: [f64; 3],
}

/// An axis-aligned box in world mm, `min` to `max` per axis: the render keeps its
/// inside. (An oriented box is six [`ClipPlane`]s.)
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CropBox {
    /// The low corner, world mm.
    pub min: [f64; 3],
    /// The high corner, world mm (above `min` along every axis).
    pub max: [f64; 3],
}

/// A half-space `normal · x + offset >= 0` (world mm, unit `normal`): the signed
/// distance of `x` from its boundary is `normal · x + offset`, positive inside.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HalfSpace {
    /// Unit normal, pointing into the kept side.
    pub normal: [f64; 3],
    /// Offset: `-normal · p` for a point `p` of the boundary.
    pub offset: f64,
}

impl HalfSpace {
    /// Signed distance (mm) of world point `x` from the boundary, positive inside.
    pub fn distance(&self, x: [f64; 3]) -> f64 {
        dot(self.normal, x) + self.offset
    }
}

/// What a render keeps of world space: any number of clip planes and an optional
/// crop box (nothing is cut by the default, empty clip).
///
/// ```
/// use glint_core::{Clip, ClipPlane, CropBox};
///
/// let clip = Clip {
///     planes: vec![ClipPlane { point: [0.0; 3], normal: [0.0, 0.0, 2.0] }],
///     crop: Some(CropBox { min: [-10.0; 3], max: [10.0; 3] }),
/// };
/// clip.validate().unwrap();
/// assert!(clip.contains([1.0, 2.0, 3.0]));
/// assert!(!clip.contains([1.0, 2.0, -3.0])); // behind the plane
/// assert!(!clip.contains([11.0, 2.0, 3.0])); // outside the box
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Clip {
    /// Planes, each keeping the side its normal points to.
    pub planes: Vec<ClipPlane>,
    /// A box keeping its inside.
    pub crop: Option<CropBox>,
}

impl Clip {
    /// Whether nothing is cut.
    pub fn is_empty(&self) -> bool {
        self.planes.is_empty() && self.crop.is_none()
    }

    /// Checks every plane and the box: finite values, a non-zero normal, a box whose
    /// `min` lies below its `max` along every axis.
    pub fn validate(&self) -> Result<(), RenderError> {
        for (i, p) in self.planes.iter().enumerate() {
            if p.point.iter().chain(&p.normal).any(|x| !x.is_finite()) {
                return Err(RenderError::Parameter(format!(
                    "clip plane {}: point and normal must be finite numbers",
                    i + 1
                )));
            }
            if dot(p.normal, p.normal).sqrt() < 1e-12 {
                return Err(RenderError::Parameter(format!(
                    "clip plane {}: the normal is zero (it must point to the side kept)",
                    i + 1
                )));
            }
        }
        if let Some(b) = &self.crop {
            if b.min.iter().chain(&b.max).any(|x| !x.is_finite()) {
                return Err(RenderError::Parameter(
                    "crop box: corners must be finite numbers".into(),
                ));
            }
            if let Some(a) = (0..3).find(|&a| b.min[a] >= b.max[a]) {
                return Err(RenderError::Parameter(format!(
                    "crop box: {} from {} to {} is empty or inverted (min must be below max)",
                    ["x", "y", "z"][a],
                    b.min[a],
                    b.max[a]
                )));
            }
        }
        Ok(())
    }

    /// The half-spaces whose intersection is kept: one per plane, then the box's six
    /// faces (x min, x max, y min, ...). Call [`Clip::validate`] first: a zero normal
    /// gives a non-finite half-space.
    pub fn half_spaces(&self) -> Vec<HalfSpace> {
        let mut out: Vec<HalfSpace> = self
            .planes
            .iter()
            .map(|p| {
                let len = dot(p.normal, p.normal).sqrt();
                let normal = p.normal.map(|x| x / len);
                HalfSpace {
                    normal,
                    offset: -dot(normal, p.point),
                }
            })
            .collect();
        if let Some(b) = &self.crop {
            for a in 0..3 {
                let mut n = [0.0; 3];
                n[a] = 1.0;
                out.push(HalfSpace {
                    normal: n,
                    offset: -b.min[a],
                });
                n[a] = -1.0;
                out.push(HalfSpace {
                    normal: n,
                    offset: b.max[a],
                });
            }
        }
        out
    }

    /// Whether world point `x` is kept (on a boundary counts as kept).
    pub fn contains(&self, x: [f64; 3]) -> bool {
        self.half_spaces().iter().all(|h| h.distance(x) >= 0.0)
    }
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_planes_and_boxes_give_one_line_each() {
        let plane = |normal| Clip {
            planes: vec![ClipPlane {
                point: [0.0; 3],
                normal,
            }],
            crop: None,
        };
        let e = plane([0.0; 3]).validate().unwrap_err().to_string();
        assert!(e.contains("clip plane 1") && e.contains("zero"), "{e}");
        let e = plane([f64::NAN, 1.0, 0.0])
            .validate()
            .unwrap_err()
            .to_string();
        assert!(e.contains("finite"), "{e}");
        let boxed = |min, max| Clip {
            planes: vec![],
            crop: Some(CropBox { min, max }),
        };
        let e = boxed([0.0; 3], [1.0, 0.0, 1.0])
            .validate()
            .unwrap_err()
            .to_string();
        assert!(e.contains("y from 0 to 0") && e.contains("empty"), "{e}");
        let e = boxed([0.0; 3], [1.0, 1.0, -1.0])
            .validate()
            .unwrap_err()
            .to_string();
        assert!(e.contains("z from 0 to -1"), "{e}");
        let e = boxed([0.0; 3], [1.0, f64::INFINITY, 1.0])
            .validate()
            .unwrap_err()
            .to_string();
        assert!(e.contains("finite"), "{e}");
        assert!(!e.contains('\n'));
        assert!(boxed([0.0; 3], [1.0; 3]).validate().is_ok());
    }

    #[test]
    fn half_spaces_keep_the_side_the_normal_points_to() {
        let clip = Clip {
            planes: vec![ClipPlane {
                point: [5.0, 0.0, 0.0],
                normal: [-3.0, 0.0, 0.0],
            }],
            crop: None,
        };
        let h = clip.half_spaces();
        assert_eq!(h.len(), 1);
        assert_eq!(h[0].distance([2.0, 7.0, 1.0]), 3.0);
        assert!(clip.contains([4.9, 0.0, 0.0]) && !clip.contains([5.1, 0.0, 0.0]));
        assert!(Clip::default().is_empty() && Clip::default().contains([1e9; 3]));
    }
}
