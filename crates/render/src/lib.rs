//! glint-render: a CPU volume ray caster for CT and MRI whose specular term is any
//! [`glint_lobe::Lobe`], evaluated for every sample.
//!
//! ```
//! use glint_lobe::{Geometry, LobeKind};
//! use glint_render::{
//!     phantom, preset, render, Field, Light, RenderSettings, Shader, camera_for,
//! };
//!
//! // The built-in Shepp-Logan head on a small grid, with glint's phantom preset.
//! let volume = phantom::shepp_logan(32).unwrap();
//! let field = Field::new(&volume).unwrap();
//! let p = preset("phantom").unwrap();
//! let tf = p.transfer_function(field.range().1 as f64).unwrap();
//! let settings = RenderSettings { width: 32, height: 32, ..Default::default() };
//! let camera = camera_for(&field, &tf, &settings).unwrap();
//! let lights = vec![(Light::HEADLIGHT.direction(&camera), 1.0)];
//! let shader = Shader::new(LobeKind::EnergyFit, 40.0, 4, Geometry::Phong, p.material(), lights, 0.0)
//!     .unwrap();
//! let image = render(&field, &tf, &shader, &settings, &|_| {}).unwrap();
//! assert_eq!(image.rgb.len(), 32 * 32);
//! assert!(image.rgb.iter().flatten().all(|c| c.is_finite()));
//! // The head covers the image's centre.
//! assert!(image.alpha[16 * 32 + 16] > 0.5);
//! ```
//!
//! The flow: a [`glint_io::Volume`] becomes a [`Field`] (values and world gradients,
//! macro cells); a [`TransferFunction`] (from a [`preset`] or JSON) classifies samples;
//! a [`Shader`] lights them (ambient + diffuse + lobe specular, Phong or Blinn
//! geometry); [`render`] casts one ray per pixel, tiles in parallel, and returns a
//! linear [`Image`] that [`Image::write_png`] writes as sRGB. To render several frames
//! of one transfer function (a moving camera, other lights or lobes), build a
//! [`Classification`] once and call [`Classification::render`] per frame.

#![warn(missing_docs)]

pub mod camera;
mod colormap;
mod error;
mod field;
mod image;
pub mod math;
pub mod phantom;
pub mod isosurface;
pub mod presets;
mod raster;
mod raycast;
mod shading;
mod tf;

pub use camera::{Camera, CameraSpec, Projection, View};
pub use colormap::{ColorMap, ScalarColors, COLORMAP_TABLE};
pub use error::RenderError;
pub use field::{Field, MACRO_CELL, MAX_FIELD_VOXELS};
pub use image::{Depth, Image};
pub use presets::{preset, Preset, PRESETS};
pub use raster::{vertex_normals, SurfaceSettings, Surfaces, SSAA_FACTORS, SURFACE_COLOR};
pub use raycast::{
    camera_for, render, Classification, Kernel, Mode, RenderSettings, RenderStats, MAX_IMAGE_SIDE,
    TERMINATION_OPACITY,
};
pub use shading::{Light, Shader};
pub use tf::{
    linear_to_srgb, srgb_to_linear, Lut, Material, MaterialOverrides, TransferFunction, LUT_SIZE,
};
