//! Where a scene puts an area light: its shape and size, a position in mm relative to
//! the volume's centre along the world axes (fixed to the patient) or along the
//! camera's axes (moving with an orbiting camera), and its radiance. Placed in the
//! world for a camera ([`AreaLightSpec::place`]) as an [`AreaLight`]; a rectangle
//! faces the volume's centre.

use serde::{Deserialize, Serialize};

use super::area::{AreaLight, MAX_AREA_RADIANCE};
use crate::camera::Camera;
use crate::error::RenderError;
use crate::math::Vec3;

/// Most area lights a scene takes (with its directional lights, at most
/// [`super::MAX_LIGHTS`] in all).
pub const MAX_AREA_LIGHTS: usize = 4;

/// Largest size (radius, edge) or offset of an area light, mm (10 m).
pub const MAX_AREA_EXTENT: f64 = 10_000.0;

/// The shape and size of an area light.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase", deny_unknown_fields)]
pub enum AreaShapeSpec {
    /// A sphere of this radius, mm.
    Sphere {
        /// Radius, mm (more than 0).
        radius: f64,
    },
    /// A rectangle of this width and height, mm, facing the volume's centre, its
    /// width along the frame's horizontal (the camera's right; the world's
    /// horizontal in the volume frame).
    Rect {
        /// Width and height, mm (each more than 0).
        size: [f64; 2],
    },
}

/// Which axes an area light's position is along.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LightFrame {
    /// The world's (RAS+, mm: right, anterior, superior) from the volume's centre:
    /// fixed to the patient.
    Volume,
    /// The camera's (right, up, towards the viewer) from the volume's centre: it
    /// turns with an orbiting camera, as the directional lights do.
    #[default]
    Camera,
}

/// An area light of a scene.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AreaLightSpec {
    /// Shape and size.
    pub shape: AreaShapeSpec,
    /// Which axes `position` is along.
    #[serde(default)]
    pub frame: LightFrame,
    /// Centre of the light, mm from the volume's centre along the frame's axes.
    pub position: [f64; 3],
    /// Linear RGB radiance it emits.
    pub radiance: [f32; 3],
}

impl AreaLightSpec {
    /// Checks the size (more than 0, finite, at most [`MAX_AREA_EXTENT`]), the
    /// position (a rectangle not at the centre, which it could not face) and the
    /// radiance.
    pub fn validate(&self) -> Result<(), RenderError> {
        let sizes: &[f64] = match &self.shape {
            AreaShapeSpec::Sphere { radius } => std::slice::from_ref(radius),
            AreaShapeSpec::Rect { size } => size,
        };
        if let Some(s) = sizes
            .iter()
            .find(|s| !(s.is_finite() && **s > 0.0 && **s <= MAX_AREA_EXTENT))
        {
            return Err(RenderError::Parameter(format!(
                "area light of size {s} mm: expected more than 0 and at most {MAX_AREA_EXTENT}"
            )));
        }
        if self
            .position
            .iter()
            .any(|p| !p.is_finite() || p.abs() > MAX_AREA_EXTENT)
        {
            return Err(RenderError::Parameter(format!(
                "area light at {:?} mm: expected finite offsets of at most {MAX_AREA_EXTENT}",
                self.position
            )));
        }
        if matches!(self.shape, AreaShapeSpec::Rect { .. }) && self.position == [0.0; 3] {
            return Err(RenderError::Parameter(
                "a rectangle light at the volume's centre faces no direction: give it an offset"
                    .into(),
            ));
        }
        if self
            .radiance
            .iter()
            .any(|c| !c.is_finite() || !(0.0..=MAX_AREA_RADIANCE).contains(c))
        {
            return Err(RenderError::Parameter(format!(
                "area light radiance {:?}: expected 0..={MAX_AREA_RADIANCE} per channel",
                self.radiance
            )));
        }
        Ok(())
    }

    /// The light in the world for `camera`, `center` the volume's centre (world mm).
    /// A rectangle at the centre itself has no direction to face: an error.
    pub fn place(&self, camera: &Camera, center: Vec3) -> Result<AreaLight, RenderError> {
        self.validate()?;
        let [x, y, z] = self.position.map(|v| v as f32);
        let (right, up, back) = match self.frame {
            LightFrame::Volume => (
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(0.0, 0.0, 1.0),
                Vec3::new(0.0, -1.0, 0.0),
            ),
            LightFrame::Camera => (camera.right, camera.up, -camera.forward),
        };
        let offset = match self.frame {
            LightFrame::Volume => Vec3::new(x, y, z),
            LightFrame::Camera => right * x + up * y + back * z,
        };
        let pos = center + offset;
        match self.shape {
            AreaShapeSpec::Sphere { radius } => {
                AreaLight::sphere(pos, radius as f32, self.radiance)
            }
            AreaShapeSpec::Rect { size } => {
                // Faces the centre: its normal along -offset, its height along the
                // frame's up made perpendicular to it (or its back, looking straight
                // down or up), its width completing u × v = n.
                let n = (offset * -1.0).normalize_or_zero();
                if n == Vec3::ZERO {
                    return Err(RenderError::Parameter(
                        "a rectangle light at the volume's centre faces no direction: give it an offset".into(),
                    ));
                }
                let mut v = up - n * up.dot(n);
                if v.length() < 1e-3 {
                    v = back - n * back.dot(n);
                }
                let v = v.normalize_or_zero();
                let u = v.cross(n);
                AreaLight::rect(pos, u * size[0] as f32, v * size[1] as f32, self.radiance)
            }
        }
    }
}
