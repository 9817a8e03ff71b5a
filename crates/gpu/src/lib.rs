//! glint-gpu: the GPU back end. WGSL compute shaders on [`wgpu`] (Vulkan, Metal, DX12)
//! render the same scene as the CPU: so far the `local` lighting model's frames
//! ([`Gpu::render_local`]: composite with point or pre-integrated sampling, MIP and
//! iso; trilinear or tricubic; clip planes and crop boxes; colour volumes; every
//! lobe, the hw lobe's table included) and the `shadows` model's
//! ([`Gpu::render_shadows_swept`]: the light volumes swept on the GPU;
//! [`Gpu::render_shadows`]: the CPU's), mirroring the CPU's reference ray caster and
//! the core's lighting term by term, checked against it on Mesa's lavapipe. The
//! adapters are listed by [`adapters`] (`glint info --devices`), and the lobe
//! micro-benchmark ([`bench_lobes`]) measures K_v against `pow` on any adapter.
//!
//! ```no_run
//! use std::sync::Arc;
//! use glint_core::Shader;
//! use glint_volume::{Classification, ClassifySettings, Field, FrameSettings, TransferFunction};
//!
//! let volume = glint_volume::phantom::shepp_logan(64).unwrap();
//! let field = Arc::new(Field::new(&volume).unwrap());
//! let tf = TransferFunction::from_flat(&[0.0, 0.0, 1.0, 0.2], &[0.0, 1.0, 1.0, 1.0]).unwrap();
//! let class = Classification::new(field, &tf, &ClassifySettings::default()).unwrap();
//! let shader = Shader::new(glint_lobe::LobeKind::EnergyFit, 40.0, 4, glint_lobe::Geometry::Phong,
//!     Default::default(), vec![glint_core::Light::HEADLIGHT], 0.0).unwrap();
//! // Any adapter, lavapipe included; `Choice::Hardware` refuses software ones.
//! let mut gpu = glint_gpu::Gpu::open(glint_gpu::Choice::Any).unwrap();
//! let frame = FrameSettings { width: 128, height: 128, ..Default::default() };
//! let image = gpu.render_local(&class, &shader, &frame).unwrap();
//! assert_eq!(image.rgb.len(), 128 * 128);
//! ```

#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod adapter;
mod bench;
mod local;
mod pages;
mod sweep;

pub use adapter::{adapters, AdapterSummary, Choice, Gpu, GpuError};
pub use bench::{bench_lobes, LobeRate};
