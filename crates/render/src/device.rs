//! The dispatch of a volume frame to the scene's [`Device`]: the GPU back end
//! (glint-gpu, cargo feature `gpu`) or, returning nothing, the CPU.

use std::sync::{Arc, Mutex};

use glint_core::{Image, RenderError, Shader};
use glint_volume::{Classification, FrameSettings};

use crate::scene::{Device, Transport};

/// A renderer's GPU, opened on first use and shared by its clones, and the notes of
/// frames that fell back to the CPU.
#[derive(Clone, Default)]
pub(crate) struct GpuSlot {
    #[cfg(feature = "gpu")]
    gpu: Option<Arc<Mutex<glint_gpu::Gpu>>>,
    /// The adapter could not be opened for `auto` (its error): not tried again.
    #[cfg(feature = "gpu")]
    unavailable: Option<String>,
    notes: Arc<Mutex<Vec<String>>>,
}

/// What the GPU back end does not render yet in a frame of `transport`, with or
/// without meshes; `None` when it renders it.
fn not_yet(transport: Transport, meshes: bool) -> Option<&'static str> {
    match transport {
        Transport::Path { .. } => Some("the path lighting model"),
        Transport::Local | Transport::Shadows(_) if meshes => Some("meshes or label surfaces"),
        Transport::Local | Transport::Shadows(_) => None,
    }
}

impl GpuSlot {
    /// Notes on frames of `--device auto` that were rendered on the CPU (no hardware
    /// GPU, or a scene the GPU does not render yet), each once; taken, so a caller
    /// prints each once.
    pub(crate) fn take_notes(&mut self) -> Vec<String> {
        std::mem::take(&mut *self.notes.lock().expect("notes lock"))
    }

    fn note(&self, note: String) {
        let mut notes = self.notes.lock().expect("notes lock");
        if !notes.contains(&note) {
            notes.push(note);
        }
    }

    /// A frame the GPU does not render, because of `why`: an error for `gpu`; for
    /// `auto` a note (kept once) and the CPU.
    fn decline(
        &self,
        device: Device,
        why: impl std::fmt::Display,
    ) -> Result<Option<Image>, RenderError> {
        if device == Device::Gpu {
            return Err(RenderError::Parameter(format!("--device gpu: {why}")));
        }
        self.note(format!("--device auto: {why}; rendering on the CPU"));
        Ok(None)
    }

    /// The frame of `class` (with meshes or not) on the scene's `device`: `Ok(None)`
    /// when it is rendered on the CPU (`cpu`, or `auto` falling back, with a note),
    /// the GPU's image otherwise; an error for `gpu` when the GPU cannot render it.
    pub(crate) fn frame(
        &mut self,
        device: Device,
        (class, shader, frame, meshes): (&Classification, &Shader, &FrameSettings, bool),
        transport: Transport,
    ) -> Result<Option<Image>, RenderError> {
        if device == Device::Cpu {
            return Ok(None);
        }
        if let Some(what) = not_yet(transport, meshes) {
            return self.decline(
                device,
                format!("the GPU back end does not render {what} yet"),
            );
        }
        #[cfg(feature = "gpu")]
        {
            self.gpu_frame(device, (class, shader, frame), transport)
        }
        #[cfg(not(feature = "gpu"))]
        {
            let _ = (class, shader, frame);
            self.decline(device, "this glint was built without its `gpu` feature")
        }
    }

    /// The frame on the GPU: `local`, or `shadows` with its light volumes swept on
    /// the GPU (built on the CPU for a clipped frame; no occluders, as frames with
    /// meshes stay on the CPU).
    #[cfg(feature = "gpu")]
    fn gpu_frame(
        &mut self,
        device: Device,
        (class, shader, frame): (&Classification, &Shader, &FrameSettings),
        transport: Transport,
    ) -> Result<Option<Image>, RenderError> {
        use glint_gpu::{Choice, Gpu, GpuError};
        if self.gpu.is_none() {
            if let (Device::Auto, Some(e)) = (device, &self.unavailable) {
                return self.decline(device, e);
            }
            let choice = match device {
                Device::Auto => Choice::Hardware,
                _ => Choice::Any,
            };
            match Gpu::open(choice) {
                Ok(gpu) => self.gpu = Some(Arc::new(Mutex::new(gpu))),
                Err(e) => {
                    if device == Device::Auto {
                        self.unavailable = Some(e.to_string());
                    }
                    return self.decline(device, e);
                }
            }
        }
        let gpu = self.gpu.clone().expect("opened above");
        let mut gpu = gpu.lock().expect("gpu lock");
        // `auto` opened a hardware adapter; `gpu` may run on one `auto` refuses.
        if device == Device::Auto && !gpu.adapter().hardware {
            let e = GpuError::NoHardware {
                found: gpu.adapter().name.clone(),
            };
            return self.decline(device, e);
        }
        let image = match transport {
            Transport::Shadows(settings) => {
                gpu.render_shadows_swept(class, shader, frame, &settings)
            }
            _ => gpu.render_local(class, shader, frame),
        };
        match image {
            Ok(image) => Ok(Some(image)),
            Err(e) => self.decline(device, e),
        }
    }
}
