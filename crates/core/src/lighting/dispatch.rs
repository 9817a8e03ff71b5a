//! The batch form's dispatch: the AVX2 kernel where the CPU has it, else the scalar
//! form one sample at a time.

use super::batch::ShadeBatch;
use super::Shader;

impl Shader {
    /// Lights the volume samples of `batch`, whose `normal` columns hold world
    /// gradients: [`Shader::shade`] for each, bit for bit.
    pub fn shade_gradients(&self, batch: &mut ShadeBatch) {
        self.shade_batch(batch, true)
    }

    /// Lights the surface samples of `batch`, whose `normal` columns hold unit
    /// normals: [`Shader::shade_normal`] for each, bit for bit.
    pub fn shade_normals(&self, batch: &mut ShadeBatch) {
        self.shade_batch(batch, false)
    }

    fn shade_batch(&self, batch: &mut ShadeBatch, gradients: bool) {
        if !self.material().shade || batch.is_empty() {
            return;
        }
        #[cfg(target_arch = "x86_64")]
        if super::avx2::supported() {
            // SAFETY: the CPU supports AVX2 (checked at run time just above).
            return unsafe { super::avx2::shade(self, batch, gradients) };
        }
        self.shade_scalar(batch, gradients)
    }

    /// The batch lit one sample at a time by the scalar form.
    pub(super) fn shade_scalar(&self, batch: &mut ShadeBatch, gradients: bool) {
        for k in 0..batch.len {
            let (n, v, c) = batch.sample(k);
            let rgb = if gradients {
                self.shade(c, n, &self.for_ray(v))
            } else {
                self.shade_normal(c, n, v)
            };
            batch.set_color(k, rgb);
        }
    }
}
