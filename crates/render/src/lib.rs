//! glint-render: a CPU volume ray caster for CT and MRI whose specular term is any
//! [`glint_lobe::Lobe`], evaluated for every sample.
//!
//! ```
//! use glint_lobe::LobeKind;
//! use glint_render::{Input, LobeSpec, Phantom, Renderer, Scene};
//!
//! // The built-in Shepp-Logan head on a small grid; every other choice is a default
//! // that the resolved scene names.
//! let scene = Scene {
//!     input: Input::Phantom { name: Phantom::SheppLogan, size: 32 },
//!     lobe: LobeSpec { kind: LobeKind::EnergyFit.into(), n: Some(40.0), ..LobeSpec::default() },
//!     size: [32, 32],
//!     ..Scene::default()
//! };
//! let mut renderer = Renderer::open(&scene.input).unwrap();
//! let rendered = renderer.render(&scene, &|_| {}).unwrap();
//! let image = &rendered.image;
//! assert_eq!(image.rgb.len(), 32 * 32);
//! assert!(image.rgb.iter().flatten().all(|c| c.is_finite()));
//! // The head covers the image's centre.
//! assert!(image.alpha[16 * 32 + 16] > 0.5);
//! // The resolved scene renders the same image again.
//! let again = renderer.render(&rendered.scene, &|_| {}).unwrap();
//! assert_eq!(again.image.rgb, image.rgb);
//! ```
//!
//! The flow: a [`Scene`] (serialisable, versioned) names the input, the transfer
//! function or [`preset`], the material, the lobe, camera-relative lights and the
//! camera; [`Scene::resolve_for`] chooses every default and builds the settings; a
//! [`Renderer`] keeps the volume's [`Field`] (values and world gradients, macro cells)
//! and the last [`Classification`] (the transfer function tabulated, the empty-space
//! map), so frames that change only the camera, lights, lobe or size are cheap. A
//! [`Shader`] lights samples (ambient + diffuse + lobe specular, Phong or Blinn
//! geometry); the ray caster casts one ray per pixel, tiles in parallel, and returns a
//! linear [`Image`] that [`Image::write_png`] writes as sRGB.

#![warn(missing_docs)]

pub mod camera;
mod colormap;
mod error;
mod field;
mod hwlobe;
mod image;
pub mod isosurface;
pub mod math;
mod meshes;
pub mod phantom;
mod preint;
pub mod presets;
mod raster;
mod raycast;
mod scene;
mod shading;
mod tf;
mod timings;

pub use camera::{Camera, CameraSpec, Projection, View};
pub use colormap::{ColorMap, ScalarColors, COLORMAP_TABLE};
pub use error::RenderError;
pub use field::{Field, Prefilter, MACRO_CELL, MAX_FIELD_VOXELS};
pub use image::{Depth, Image, RING_BLUR_SIGMA, RING_ERODE_PX, RING_OBJECT_ALPHA};
pub use meshes::{MeshSpec, Overlay, DEFAULT_SSAA, SURFACE_MATERIAL, SURFACE_SHININESS};
pub use phantom::Phantom;
pub use preint::Sampling;
pub use presets::{preset, Preset, PRESETS};
pub use raster::{vertex_normals, SurfaceSettings, Surfaces, SSAA_FACTORS, SURFACE_COLOR};
pub use raycast::{
    Classification, ClassifySettings, FrameSettings, Kernel, Mode, RenderStats, MAX_IMAGE_SIDE,
    TERMINATION_OPACITY,
};
pub use scene::{
    Derived, Input, LobeSpec, MeshLayer, OpenedVolume, Plan, RenderMode, Rendered, Renderer,
    Resolved, Scene, SceneLobe, DEFAULT_SHININESS, MAX_SCENE_BYTES, SCENE_VERSION,
};
pub use shading::{Light, Shader, MAX_LIGHTS};
pub use tf::{
    linear_to_srgb, srgb_to_linear, Lut, Material, MaterialOverrides, TransferFunction,
    TransferFunctionFile, LUT_SIZE,
};
pub use timings::Timings;
