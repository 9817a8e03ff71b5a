//! glint-render: a CPU volume ray caster for CT and MRI whose specular term is any
//! [`glint_lobe::Lobe`], evaluated for every sample.
//!
//! ```
//! use glint_lobe::LobeKind;
//! use glint_render::{Input, LobeSpec, Phantom, ReadOptions, Renderer, Scene};
//!
//! // The built-in Shepp-Logan head on a small grid; every other choice is a default
//! // that the resolved scene names.
//! let scene = Scene {
//!     input: Input::Phantom { name: Phantom::SheppLogan, size: 32 },
//!     lobe: LobeSpec { kind: LobeKind::EnergyFit.into(), n: Some(40.0), ..LobeSpec::default() },
//!     size: [32, 32],
//!     ..Scene::default()
//! };
//! let mut renderer = Renderer::open(&scene, &ReadOptions::default()).unwrap();
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
//! linear [`Image`] that [`Image::write_png`] writes as sRGB. A [`Turntable`] renders a
//! scene from cameras stepping round it with one renderer and writes the frames with an
//! [`AnimationWriter`] (an animated GIF, an MP4 through ffmpeg, or PNG frames).
//!
//! This crate is the facade of the renderer crates, each with one job, whose
//! dependencies point one way (front ends -> glint-render -> glint-volume,
//! glint-raster, glint-mesh -> glint-core -> glint-lobe; glint-io below them all):
//!
//! | crate | job |
//! | --- | --- |
//! | [`glint_core`] | vector math, cameras, images and PNG, colour, colour maps, the lighting model, timings, the error type |
//! | [`glint_volume`] | the field, transfer functions and pre-integration, presets, the built-in phantoms, the ray caster and its SIMD march |
//! | [`glint_raster`] | the mesh rasterizer |
//! | [`glint_mesh`] | isosurface extraction, vertex normals, smoothing (no image or font dependencies) |
//! | [`glint_labels`] | label maps: colour tables, label statistics, per-label surfaces |
//! | glint-render | the [`Scene`] value and its files, the [`Renderer`], the hardware lobe |
//!
//! It re-exports what front ends use, so they depend on it alone.

#![warn(missing_docs)]
// No unsafe code, but for Intel Open Image Denoise's C API, loaded at run time
// (src/denoise/oidn.rs).
#![deny(unsafe_code)]

mod animation;
mod camera_path;
pub mod denoise;
mod device;
mod hwlobe;
mod labels;
mod meshes;
mod pick;
mod renderer;
mod scene;
mod turntable;
mod webp;

pub use animation::{
    AnimationFormat, AnimationWriter, TurntableError, ANIMATION_FORMATS, DEFAULT_TURNTABLE_FPS,
    MAX_TURNTABLE_FPS, MAX_TURNTABLE_FRAMES,
};
pub use camera_path::{CameraKey, CameraPath, CameraPathError, MAX_CAMERA_KEYS};
pub use denoise::Denoise;
pub use glint_core::lighting::{AreaLightSpec, AreaShapeSpec, LightFrame};
pub use glint_core::Legend;
pub use glint_core::{camera, math};
pub use glint_core::{
    linear_to_srgb, luminance, luminance_f32, srgb_to_linear, Camera, CameraSpec, ColorMap, Depth,
    Image, Light, Material, MaterialOverrides, Projection, RenderError, RenderMode, RenderStats,
    ScalarColors, Shader, Timings, View, COLORMAP_TABLE, MAX_IMAGE_SIDE, MAX_LIGHTS,
    RING_BLUR_SIGMA, RING_ERODE_PX, RING_OBJECT_ALPHA,
};
pub use glint_core::{tone_map, FloatFormat, Focus, Tone};
pub use glint_core::{Clip, ClipPlane, CropBox, HalfSpace};
/// The GPU back end (feature `gpu`): adapters, the device, the lobe micro-benchmark.
#[cfg(feature = "gpu")]
pub use glint_gpu as gpu;
pub use glint_io::ReadOptions;
pub use glint_labels as label_maps;
pub use glint_labels::default_label_smoothing;
pub use glint_mesh as mesh;
pub use glint_mesh::vertex_normals;
pub use glint_raster::{SurfaceSettings, Surfaces, SSAA_FACTORS, SURFACE_COLOR};
pub use glint_volume::{memory_limit, set_memory_limit};
pub use glint_volume::{phantom, presets};
pub use glint_volume::{
    preset, Classification, ClassifySettings, Field, Filter, FrameSettings, Kernel, Phantom,
    Prefilter, Preset, Sampling, Source, TfFormat, TransferFunction, TransferFunctionFile,
    WindowLevel, MACRO_CELL, MAX_FIELD_VOXELS, PICK_OPACITY, PRESETS, TERMINATION_OPACITY,
};
pub use glint_volume::{
    LightingModel, PathImage, PathSettings, Sampler, ShadowField, ShadowSettings, MAX_BOUNCES,
    MAX_SPP,
};
pub use glint_volume::{PathFeatures, FEATURE_OPACITY};
pub use labels::{label_read_options, LabelSpec, LabelsAs, PickLabel};
pub use meshes::{MeshSpec, Overlay, DEFAULT_SSAA, SURFACE_MATERIAL, SURFACE_SHININESS};
pub use pick::{image_point, Pick, PickedObject};
pub use renderer::{InMemory, Rendered, Renderer};
pub use scene::{
    available_environments, fetched_environment, load_environment, Derived, Device, Input,
    Lighting, LobeSpec, MeshLayer, OpenedVolume, Plan, Resolved, Scene, SceneLobe, Transport,
    DEFAULT_BOUNCES, DEFAULT_ENVIRONMENT, DEFAULT_SHININESS, DEFAULT_SPP, ENVIRONMENT_NAMES,
    FETCHED_ENVIRONMENTS, MAX_SCENE_BYTES, MERGED_FIELDS, SCENE_VERSION,
};
pub use turntable::{Turntable, TurntableWritten};

/// A mesh-extraction error as the renderer's: the same variant and message.
pub(crate) fn mesh_error(e: glint_mesh::MeshError) -> RenderError {
    match e {
        glint_mesh::MeshError::Volume(s) => RenderError::Volume(s),
        glint_mesh::MeshError::Parameter(s) => RenderError::Parameter(s),
        glint_mesh::MeshError::Mesh(e) => RenderError::Mesh(e),
        other => RenderError::Volume(other.to_string()),
    }
}
