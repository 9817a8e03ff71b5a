//! glint-volume: CPU volume rendering of CT and MRI. A [`Field`] holds a volume's
//! reconstruction values, world gradients and macro-cell ranges; a
//! [`TransferFunction`] (or one of 3D Slicer's [`presets`]) classifies it into a
//! [`Classification`] (the function tabulated, point-sampled or pre-integrated, and the
//! empty-space map); frames are ray cast from it, every sample lit by a
//! [`glint_core::Shader`]. The built-in [`phantom`]s are analytic test volumes with
//! presets of their own.
//!
//! ```
//! use std::sync::Arc;
//! use glint_core::{Light, Material, RenderMode, Shader};
//! use glint_io::{Samples, Volume};
//! use glint_lobe::{Geometry, LobeKind};
//! use glint_volume::{
//!     Classification, ClassifySettings, Field, FrameSettings, TransferFunction, Transport,
//! };
//!
//! // A ball of value 1 in a 16^3 volume of 0.
//! let n = 16;
//! let values: Vec<f32> = (0..n * n * n)
//!     .map(|i| {
//!         let p = [i % n, i / n % n, i / (n * n)].map(|x| x as f32 - 7.5);
//!         if p.iter().map(|x| x * x).sum::<f32>() < 25.0 { 1.0 } else { 0.0 }
//!     })
//!     .collect();
//! let volume = Volume::new([n; 3], [1.0; 3], Samples::F32(values)).unwrap();
//! let field = Arc::new(Field::new(&volume).unwrap());
//! let tf = TransferFunction::from_flat(&[0.0, 0.0, 0.5, 0.0, 1.0, 1.0], &[0.0, 1.0, 1.0, 1.0]).unwrap();
//! let settings = ClassifySettings { mode: RenderMode::Composite, ..Default::default() };
//! let class = Classification::new(field, &tf, &settings).unwrap();
//! let shader = Shader::new(LobeKind::EnergyFit, 40.0, 4, Geometry::Phong,
//!     Material::default(), vec![Light::HEADLIGHT], 0.0).unwrap();
//! let frame = FrameSettings { width: 32, height: 32, ..Default::default() };
//! let image = class.frame(&shader, &frame, None, Transport::Local, &|_| {}).unwrap();
//! // The ball covers the image's centre, not its corner.
//! assert!(image.alpha[16 * 32 + 16] > 0.9);
//! assert_eq!(image.alpha[0], 0.0);
//! ```

#![warn(missing_docs)]

mod classification;
mod clip;
mod device;
mod field;
mod frames;
mod light;
pub mod phantom;
mod raycast;
pub mod transport;

pub use classification::presets;
pub use classification::{
    Classification, ClassifySettings, ColourVolume, Lut, PreIntegratedTables, Sampling, TfFormat,
    TransferFunction, TransferFunctionFile, WindowLevel, LUT_SIZE,
};
pub use device::{DeviceClip, LocalMarch, VoxelGrids};
pub use field::{
    memory_limit, open_zarr, set_memory_limit, Field, Filter, Prefilter, Source, MACRO_CELL,
    MAX_FIELD_VOXELS, MIN_BRICK_SLOTS, PROCESS_OVERHEAD,
};
pub use frames::Transport;
pub use light::{LightGridView, LightSweep, LightSweeps};
pub use phantom::Phantom;
pub use presets::{preset, Preset, PRESETS};
pub use raycast::{
    FrameSettings, Kernel, LabelLook, LabelVolume, PathFeatures, VolumeHit, FEATURE_OPACITY,
    PICK_OPACITY, TERMINATION_OPACITY,
};
pub use transport::{
    check_spp, check_time_budget, LightingModel, Occluders, PathImage, PathSettings, Sampler,
    ShadowField, ShadowSettings, ADAPTIVE_MIN_SAMPLES, ADAPTIVE_THRESHOLD, MAX_BOUNCES, MAX_SPP,
    MAX_TIME_BUDGET_MS,
};
