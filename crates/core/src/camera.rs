//! Cameras: named anatomical views in the volume's world frame (RAS+), orbit angles,
//! zoom, perspective or orthographic projection.

use serde::{Deserialize, Serialize};

use crate::error::RenderError;
use crate::math::Vec3;

/// A named view: where the camera stands relative to the patient, in RAS+.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    Serialize,
    Deserialize,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::Display,
    strum::VariantNames,
    strum::VariantArray,
)]
#[serde(rename_all = "lowercase")]
#[strum(serialize_all = "lowercase", ascii_case_insensitive, parse_err_ty = RenderError, parse_err_fn = crate::error::unknown_name::<Self>)]
pub enum View {
    /// In front of the face, looking towards posterior; superior up.
    #[default]
    #[strum(to_string = "anterior", serialize = "a")]
    Anterior,
    /// Behind the head, looking towards anterior; superior up.
    #[strum(to_string = "posterior", serialize = "p")]
    Posterior,
    /// At the patient's left, looking towards the right; superior up.
    #[strum(to_string = "left", serialize = "l")]
    Left,
    /// At the patient's right, looking towards the left; superior up.
    #[strum(to_string = "right", serialize = "r")]
    Right,
    /// Above, looking down towards inferior; anterior up.
    #[strum(to_string = "superior", serialize = "s")]
    Superior,
    /// Below, looking up towards superior; anterior up.
    #[strum(to_string = "inferior", serialize = "i")]
    Inferior,
}

impl View {
    /// All views.
    pub const ALL: &'static [View] = <View as strum::VariantArray>::VARIANTS;

    /// The names users type, in the order of [`View::ALL`].
    pub const NAMES: &'static [&'static str] = <View as strum::VariantNames>::VARIANTS;

    /// The name users type.
    pub fn name(self) -> &'static str {
        self.into()
    }

    /// Unit vector from the focal point to the eye, and the up vector (RAS+).
    pub fn eye_and_up(self) -> (Vec3, Vec3) {
        let s = Vec3::new(0.0, 0.0, 1.0);
        let a = Vec3::new(0.0, 1.0, 0.0);
        match self {
            View::Anterior => (a, s),
            View::Posterior => (-a, s),
            View::Left => (Vec3::new(-1.0, 0.0, 0.0), s),
            View::Right => (Vec3::new(1.0, 0.0, 0.0), s),
            View::Superior => (s, a),
            View::Inferior => (-s, a),
        }
    }
}

impl glint_lobe::names::Named for View {
    const WHAT: &'static str = "view";
}

/// Perspective or orthographic projection.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    Serialize,
    Deserialize,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::Display,
    strum::VariantNames,
    strum::VariantArray,
)]
#[serde(rename_all = "lowercase")]
#[strum(serialize_all = "lowercase", ascii_case_insensitive, parse_err_ty = RenderError, parse_err_fn = crate::error::unknown_name::<Self>)]
pub enum Projection {
    /// Pinhole camera with a 30° vertical field of view (VTK's default).
    #[default]
    #[strum(to_string = "perspective", serialize = "persp")]
    Perspective,
    /// Parallel rays.
    #[strum(
        to_string = "orthographic",
        serialize = "ortho",
        serialize = "parallel"
    )]
    Orthographic,
}

impl Projection {
    /// Both projections, perspective first.
    pub const ALL: &'static [Projection] = <Projection as strum::VariantArray>::VARIANTS;

    /// The names users type, in the order of [`Projection::ALL`].
    pub const NAMES: &'static [&'static str] = <Projection as strum::VariantNames>::VARIANTS;

    /// The name users type.
    pub fn name(self) -> &'static str {
        self.into()
    }
}

impl glint_lobe::names::Named for Projection {
    const WHAT: &'static str = "projection";
}

/// Vertical field of view of the perspective camera, degrees (VTK's `vtkCamera`
/// default ViewAngle).
pub const FIELD_OF_VIEW_DEG: f64 = 30.0;

/// A camera placed in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position (perspective) or the centre of the image plane (orthographic), mm.
    pub eye: Vec3,
    /// Unit viewing direction.
    pub forward: Vec3,
    /// Unit vector to the image's right.
    pub right: Vec3,
    /// Unit vector to the image's top.
    pub up: Vec3,
    /// Projection.
    pub projection: Projection,
    /// Perspective: tangent of half the vertical field of view. Orthographic: half the
    /// image height in mm.
    pub half_height: f32,
    /// Thin lens: the lens's radius in mm; 0 is a pinhole ([`Camera::lens_ray`]).
    pub lens_radius: f32,
    /// Thin lens: distance in mm from the eye (the image plane's centre, orthographic)
    /// along `forward` to the plane in focus; unused by a pinhole.
    pub focus_distance: f32,
}

/// Where a thin-lens camera focuses ([`CameraSpec::focus`]): a distance in mm from
/// the eye along the view axis, or `auto`: the first opaque point under the image's
/// centre (found by the renderer, which picks it). In JSON a number or `"auto"`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Focus {
    /// Focus at this distance, mm.
    Distance(f64),
    /// Focus on what the image's centre shows.
    Auto(AutoFocus),
}

/// The word `auto` of [`Focus::Auto`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AutoFocus {
    /// `"auto"`.
    Auto,
}

impl Focus {
    /// Autofocus.
    pub const AUTO: Focus = Focus::Auto(AutoFocus::Auto);
}

impl std::str::FromStr for Focus {
    type Err = RenderError;

    /// `auto`, or a distance in mm (checked by [`CameraSpec::validate`]).
    fn from_str(s: &str) -> Result<Focus, RenderError> {
        let s = s.trim();
        if s.eq_ignore_ascii_case("auto") {
            return Ok(Focus::AUTO);
        }
        s.parse::<f64>().map(Focus::Distance).map_err(|_| {
            RenderError::Parameter(format!("focus '{s}': expected a distance in mm or 'auto'"))
        })
    }
}

/// Whether `x` is zero (serde's `skip_serializing_if` for the pinhole's aperture).
fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

/// How to place a camera around a bounding sphere.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CameraSpec {
    /// The named starting view.
    pub view: View,
    /// Degrees to orbit about the view's up axis (positive: the camera moves right).
    pub azimuth: f64,
    /// Degrees to orbit about the camera's right axis (positive: the camera moves up).
    pub elevation: f64,
    /// Magnification: 1 fits the bounding sphere into the image's shorter side.
    pub zoom: f64,
    /// Projection.
    pub projection: Projection,
    /// Thin-lens depth of field (`path` lighting only): the lens's radius in mm; 0,
    /// the default, is a pinhole. Left out of the JSON while 0.
    #[serde(skip_serializing_if = "is_zero")]
    pub aperture: f64,
    /// Where a lens of [`aperture`](Self::aperture) > 0 focuses (default: `auto`).
    /// Left out of the JSON when absent.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub focus: Option<Focus>,
}

impl Default for CameraSpec {
    fn default() -> Self {
        CameraSpec {
            view: View::Anterior,
            azimuth: 0.0,
            elevation: 0.0,
            zoom: 1.0,
            projection: Projection::Perspective,
            aperture: 0.0,
            focus: None,
        }
    }
}

impl CameraSpec {
    /// Checks the angles (finite, within ±3600°), the zoom (0.001..=1000), the
    /// aperture (finite, 0..=10000 mm) and a focus distance (finite, > 0).
    pub fn validate(&self) -> Result<(), RenderError> {
        if !self.aperture.is_finite() || !(0.0..=1e4).contains(&self.aperture) {
            return Err(RenderError::Parameter(format!(
                "aperture = {}: expected a lens radius in mm, 0 (a pinhole) to 10000",
                self.aperture
            )));
        }
        if let Some(Focus::Distance(d)) = self.focus {
            if !d.is_finite() || d <= 0.0 {
                return Err(RenderError::Parameter(format!(
                    "focus = {d}: expected a distance in mm greater than 0, or 'auto'"
                )));
            }
        }
        for (name, x) in [("azimuth", self.azimuth), ("elevation", self.elevation)] {
            if !x.is_finite() || x.abs() > 3600.0 {
                return Err(RenderError::Parameter(format!(
                    "{name} = {x}: expected finite degrees within ±3600"
                )));
            }
        }
        if !self.zoom.is_finite() || !(1e-3..=1e3).contains(&self.zoom) {
            return Err(RenderError::Parameter(format!(
                "zoom = {}: expected a number in 0.001..=1000",
                self.zoom
            )));
        }
        Ok(())
    }
}

fn rotate(v: Vec3, axis: Vec3, deg: f64) -> Vec3 {
    // Rodrigues' rotation formula.
    let (s, c) = (deg.to_radians().sin() as f32, deg.to_radians().cos() as f32);
    v * c + axis.cross(v) * s + axis * (axis.dot(v) * (1.0 - c))
}

impl Camera {
    /// Places a camera looking at `center` so a sphere of `radius` fills the shorter
    /// side of a `width` x `height` image at zoom 1.
    pub fn frame(
        spec: &CameraSpec,
        center: Vec3,
        radius: f32,
        width: u32,
        height: u32,
    ) -> Result<Camera, RenderError> {
        spec.validate()?;
        let (to_eye, up0) = spec.view.eye_and_up();
        // Azimuth about the up axis; positive turns the eye towards the image's right.
        let right0 = (-to_eye).cross(up0);
        let to_eye = rotate(to_eye, up0, spec.azimuth);
        let right = rotate(right0, up0, spec.azimuth);
        // Elevation about the right axis; positive raises the eye.
        let to_eye = rotate(to_eye, right, -spec.elevation).normalize_or_zero();
        let up = right.cross(-to_eye).normalize_or_zero();
        let forward = -to_eye;
        let right = forward.cross(up).normalize_or_zero();
        // The shorter image side sees the whole sphere.
        let aspect_min = (width.min(height) as f32) / (height as f32);
        let zoom = spec.zoom as f32;
        let radius = radius.max(1e-3);
        let half_fov = (FIELD_OF_VIEW_DEG / 2.0).to_radians() as f32;
        let (eye, half_height) = match spec.projection {
            Projection::Perspective => {
                let dist = radius / half_fov.sin();
                let t = half_fov.tan() / zoom / aspect_min;
                (center + to_eye * dist, t)
            }
            Projection::Orthographic => {
                (center + to_eye * (2.0 * radius), radius / zoom / aspect_min)
            }
        };
        Ok(Camera {
            eye,
            forward,
            right,
            up,
            projection: spec.projection,
            half_height,
            lens_radius: spec.aperture as f32,
            focus_distance: match spec.focus {
                Some(Focus::Distance(d)) => d as f32,
                // Resolved by the renderer before a lens ray is traced.
                _ => 0.0,
            },
        })
    }

    /// The image plane of a `width` x `height` image: pixel `(x, y)` (row 0 at the
    /// top) has its centre at `u = u0 + x du` along `right` and `v = v0 + y dv` along
    /// `up`; returns `[u0, du, v0, dv]`. Perspective: at unit distance from the eye;
    /// orthographic: in mm from the image centre.
    pub fn image_plane(&self, width: u32, height: u32) -> [f32; 4] {
        let (w, h) = (width as f32, height as f32);
        let (hh, aspect) = (self.half_height, w / h);
        // u = (2 (x + 0.5) / w - 1) hh aspect, v = (1 - 2 (y + 0.5) / h) hh.
        [
            (1.0 / w - 1.0) * hh * aspect,
            2.0 / w * hh * aspect,
            (1.0 - 1.0 / h) * hh,
            -2.0 / h * hh,
        ]
    }

    /// Origin and unit direction of the ray through pixel `(x, y)` (row 0 at the top)
    /// of a `width` x `height` image, through the pixel's centre.
    #[inline]
    pub fn ray(&self, x: f32, y: f32, width: u32, height: u32) -> (Vec3, Vec3) {
        let [u0, du, v0, dv] = self.image_plane(width, height);
        let (u, v) = (u0 + x * du, v0 + y * dv);
        match self.projection {
            Projection::Perspective => {
                let d = (self.forward + self.right * u + self.up * v).normalize_or_zero();
                (self.eye, d)
            }
            Projection::Orthographic => (self.eye + self.right * u + self.up * v, self.forward),
        }
    }

    /// Whether the camera has a lens (a radius > 0 and a plane in focus at a finite
    /// distance > 0): [`Camera::lens_ray`] then needs a point of the lens. A radius with
    /// no usable focus distance is a pinhole, not a lens focused behind the eye.
    #[inline]
    pub fn has_lens(&self) -> bool {
        self.lens_radius > 0.0 && self.focus_distance > 0.0 && self.focus_distance.is_finite()
    }

    /// The ray through pixel `(x, y)` ([`Camera::ray`]) of a thin lens (Kolb,
    /// Mitchell and Hanrahan 1995; pbrt-v4's `PerspectiveCamera`): it leaves the point
    /// of the lens `lens` (two uniform numbers in `[0, 1)`, mapped to the disc of
    /// radius [`lens_radius`](Self::lens_radius) concentrically, Shirley and Chiu
    /// 1997) towards where the pinhole ray meets the plane in focus, at
    /// [`focus_distance`](Self::focus_distance) along `forward`. A pinhole, or `None`,
    /// gives [`Camera::ray`] exactly.
    #[inline]
    pub fn lens_ray(&self, x: f32, y: f32, w: u32, h: u32, lens: Option<[f32; 2]>) -> (Vec3, Vec3) {
        let (o, d) = self.ray(x, y, w, h);
        let Some(lens) = lens.filter(|_| self.has_lens()) else {
            return (o, d);
        };
        let along = d.dot(self.forward);
        if along <= 0.0 {
            return (o, d);
        }
        let focus = o + d * (self.focus_distance / along);
        let [lx, ly] = concentric_disc(lens);
        let origin = o + (self.right * lx + self.up * ly) * self.lens_radius;
        (origin, (focus - origin).normalize_or_zero())
    }
}

/// Shirley and Chiu's concentric map of the unit square onto the unit disc (area
/// preserving, low distortion), as pbrt-v4's `SampleUniformDiskConcentric`.
#[inline]
fn concentric_disc([u, v]: [f32; 2]) -> [f32; 2] {
    let (a, b) = (2.0 * u - 1.0, 2.0 * v - 1.0);
    if a == 0.0 && b == 0.0 {
        return [0.0, 0.0];
    }
    let quarter = std::f32::consts::FRAC_PI_4;
    let (r, theta) = if a.abs() > b.abs() {
        (a, quarter * (b / a))
    } else {
        (b, 2.0 * quarter - quarter * (a / b))
    };
    [r * theta.cos(), r * theta.sin()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_print_and_parse_as_users_type_them() {
        let names: Vec<&str> = View::ALL.iter().map(|v| v.name()).collect();
        assert_eq!(
            names,
            [
                "anterior",
                "posterior",
                "left",
                "right",
                "superior",
                "inferior"
            ]
        );
        assert_eq!(View::NAMES, names.as_slice());
        for (short, v) in ["a", "p", "l", "r", "s", "i"].iter().zip(View::ALL) {
            assert_eq!(short.parse::<View>().unwrap(), *v);
            assert_eq!(v.name().to_uppercase().parse::<View>().unwrap(), *v);
        }
        assert_eq!(Projection::Perspective.to_string(), "perspective");
        assert_eq!(Projection::Orthographic.name(), "orthographic");
        for (s, p) in [
            ("perspective", Projection::Perspective),
            ("persp", Projection::Perspective),
            ("orthographic", Projection::Orthographic),
            ("ortho", Projection::Orthographic),
            ("Parallel", Projection::Orthographic),
        ] {
            assert_eq!(s.parse::<Projection>().unwrap(), p);
        }
        let err = "fisheye".parse::<Projection>().unwrap_err().to_string();
        assert!(err.contains("perspective, orthographic"), "{err}");
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-5
    }

    #[test]
    fn named_views_look_at_the_patient_from_the_named_side() {
        let c = Camera::frame(
            &CameraSpec {
                view: View::Left,
                ..Default::default()
            },
            Vec3::ZERO,
            100.0,
            64,
            64,
        )
        .unwrap();
        // From the patient's left the camera looks towards +x (the patient's right);
        // image right = forward x up = x cross z = -y: anterior is on the image's left.
        assert!(close(c.forward, Vec3::new(1.0, 0.0, 0.0)));
        assert!(close(c.up, Vec3::new(0.0, 0.0, 1.0)));
        assert!(close(c.right, Vec3::new(0.0, -1.0, 0.0)));
        assert!(c.eye.x < -100.0);
    }

    #[test]
    fn azimuth_90_from_anterior_is_the_patients_left_or_right() {
        // Anterior view: eye at +y, right = -x (the patient's right is on the image's
        // left, as in a face-to-face view). Orbiting the eye towards the image's right
        // brings it to -x: the patient's left.
        let spec = CameraSpec {
            azimuth: 90.0,
            ..Default::default()
        };
        let c = Camera::frame(&spec, Vec3::ZERO, 1.0, 8, 8).unwrap();
        let left = Camera::frame(
            &CameraSpec {
                view: View::Left,
                ..Default::default()
            },
            Vec3::ZERO,
            1.0,
            8,
            8,
        )
        .unwrap();
        assert!(close(c.forward, left.forward), "{:?}", c.forward);
        let e = Camera::frame(
            &CameraSpec {
                elevation: 90.0,
                ..Default::default()
            },
            Vec3::ZERO,
            1.0,
            8,
            8,
        )
        .unwrap();
        assert!(
            close(e.forward, Vec3::new(0.0, 0.0, -1.0)),
            "{:?}",
            e.forward
        );
    }

    #[test]
    fn perspective_frames_the_sphere() {
        // The ray through the top edge's centre is tangent to the sphere at zoom 1.
        let c = Camera::frame(&CameraSpec::default(), Vec3::ZERO, 10.0, 100, 100).unwrap();
        let (o, d) = c.ray(49.5, -0.5, 100, 100);
        // Distance from the centre to the ray equals the radius.
        let t = (-o).dot(d);
        let closest = o + d * t;
        assert!(
            (closest.length() - 10.0).abs() < 1e-3,
            "{}",
            closest.length()
        );
    }

    #[test]
    fn bad_parameters_are_rejected() {
        let bad = CameraSpec {
            zoom: 0.0,
            ..Default::default()
        };
        assert!(Camera::frame(&bad, Vec3::ZERO, 1.0, 8, 8).is_err());
        assert!("sideways".parse::<View>().is_err());
        assert_eq!("L".parse::<View>().unwrap(), View::Left);
    }

    #[test]
    fn a_thin_lens_focuses_its_rays_on_the_plane_in_focus() {
        let spec = CameraSpec {
            aperture: 5.0,
            focus: Some(Focus::Distance(120.0)),
            ..Default::default()
        };
        for projection in [Projection::Perspective, Projection::Orthographic] {
            let spec = CameraSpec { projection, ..spec };
            let c = Camera::frame(&spec, Vec3::ZERO, 50.0, 40, 30).unwrap();
            assert_eq!((c.lens_radius, c.focus_distance), (5.0, 120.0));
            let (o, d) = c.ray(7.0, 21.0, 40, 30);
            // No lens point: the pinhole ray, bit for bit.
            assert_eq!(c.lens_ray(7.0, 21.0, 40, 30, None), (o, d));
            let focus = o + d * (120.0 / d.dot(c.forward));
            for lens in [[0.0, 0.0], [0.9, 0.1], [0.5, 0.5], [0.25, 0.999]] {
                let (lo, ld) = c.lens_ray(7.0, 21.0, 40, 30, Some(lens));
                // The lens point lies on the lens's disc, in the plane of the eye.
                let off = lo - o;
                assert!(off.length() <= 5.0 + 1e-4 && off.dot(c.forward).abs() < 1e-4);
                // Every ray meets the pinhole ray on the plane in focus.
                let t = (focus - lo).dot(c.forward) / ld.dot(c.forward);
                assert!(close(lo + ld * t, focus), "{projection:?} {lens:?}");
            }
        }
        // A pinhole ignores the lens point.
        let c = Camera::frame(&CameraSpec::default(), Vec3::ZERO, 50.0, 40, 30).unwrap();
        assert_eq!(
            c.lens_ray(3.0, 4.0, 40, 30, Some([0.9, 0.9])),
            c.ray(3.0, 4.0, 40, 30)
        );
        // So does a lens with no usable plane in focus (at or behind the eye, or at
        // infinity): a pinhole, not rays converging behind the camera.
        for focus_distance in [0.0, -10.0, f32::INFINITY, f32::NAN] {
            let c = Camera {
                lens_radius: 5.0,
                focus_distance,
                ..c
            };
            assert!(!c.has_lens(), "{focus_distance}");
            assert_eq!(
                c.lens_ray(3.0, 4.0, 40, 30, Some([0.9, 0.9])),
                c.ray(3.0, 4.0, 40, 30)
            );
        }
    }

    #[test]
    fn aperture_and_focus_are_checked_and_parsed() {
        let bad = |aperture, focus| {
            CameraSpec {
                aperture,
                focus,
                ..Default::default()
            }
            .validate()
            .unwrap_err()
            .to_string()
        };
        assert!(bad(-1.0, None).contains("aperture = -1"));
        assert!(bad(f64::NAN, None).contains("aperture"));
        assert!(bad(1.0, Some(Focus::Distance(0.0))).contains("focus = 0"));
        assert!(bad(1.0, Some(Focus::Distance(-5.0))).contains("focus = -5"));
        assert_eq!("auto".parse::<Focus>().unwrap(), Focus::AUTO);
        assert_eq!("250".parse::<Focus>().unwrap(), Focus::Distance(250.0));
        assert!("near".parse::<Focus>().is_err());
        // JSON: a number or "auto"; the defaults are left out.
        let spec: CameraSpec =
            serde_json::from_str(r#"{"aperture": 2.5, "focus": "auto"}"#).unwrap();
        assert_eq!((spec.aperture, spec.focus), (2.5, Some(Focus::AUTO)));
        let spec: CameraSpec = serde_json::from_str(r#"{"focus": 300}"#).unwrap();
        assert_eq!(spec.focus, Some(Focus::Distance(300.0)));
        let json = serde_json::to_string(&CameraSpec::default()).unwrap();
        assert!(
            !json.contains("aperture") && !json.contains("focus"),
            "{json}"
        );
    }
}
