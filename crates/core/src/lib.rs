//! glint-core: what every glint renderer shares. Plain vector math ([`Vec3`]), cameras
//! framed on a bounding sphere ([`Camera`]), linear images written as sRGB PNG
//! ([`Image`]), colour encodings and colour maps, the one lighting model (ambient +
//! diffuse + a [`glint_lobe`] specular lobe for camera-relative [`Light`]s, Phong or
//! Blinn geometry: [`Shader`]), the render mode, stage timings and the error type of
//! the renderer crates.
//!
//! ```
//! use glint_core::{Camera, CameraSpec, Light, Material, Shader, Vec3};
//! use glint_lobe::{Geometry, LobeKind};
//!
//! // A camera looking at a sphere of radius 1 at the origin, and a shader with the
//! // paper's lobe K_4 (n = 40) lit by the headlight.
//! let camera = Camera::frame(&CameraSpec::default(), Vec3::ZERO, 1.0, 64, 64).unwrap();
//! let shader = Shader::new(LobeKind::EnergyFit, 40.0, 4, Geometry::Phong,
//!     Material::default(), vec![Light::HEADLIGHT], 0.0).unwrap().placed(&camera);
//! // A surface facing the viewer reflects the headlight straight back: ambient +
//! // diffuse + the full specular coefficient.
//! let view = -camera.forward;
//! let lit = shader.shade_normal([1.0; 3], view, view);
//! let m = Material::default();
//! assert!((lit[0] - (m.ambient + m.diffuse + m.specular)).abs() < 1e-6);
//! ```

#![warn(missing_docs)]

pub mod camera;
mod clip;
pub mod color;
mod colormap;
mod error;
mod float_image;
mod image;
mod legend;
pub mod lighting;
pub mod math;
mod mode;
mod timings;
pub mod tone;

pub use camera::{Camera, CameraSpec, Focus, Projection, View};
pub use clip::{Clip, ClipPlane, CropBox, HalfSpace};
pub use color::{linear_to_srgb, luminance, luminance_f32, srgb_to_linear, REC709_LUMA};
pub use colormap::{ColorMap, ScalarColors, COLORMAP_TABLE};
pub use error::{unknown_name, BoxedError, RenderError};
pub use float_image::FloatFormat;
pub use image::{
    Depth, Image, RenderStats, MAX_IMAGE_SIDE, RING_BLUR_SIGMA, RING_ERODE_PX, RING_OBJECT_ALPHA,
};
pub use legend::Legend;
pub use lighting::{
    check_env_size, phase_hg, power_heuristic, Bsdf, BsdfSample, EnvMap, EnvSample, Light,
    Material, MaterialOverrides, RayLighting, Scattering, ShadeBatch, Shader, SurfacePart,
    MAX_ANISOTROPY, MAX_LIGHTS, MEDIUM_IRRADIANCE,
};
pub use math::Vec3;
pub use mode::RenderMode;
pub use timings::Timings;
pub use tone::{tone_map, Tone};
