//! Per-pixel lighting of surfaces with a [`Shader`]'s lobe, geometry, material and
//! lights: the volume renderer's model (ambient + diffuse + lobe specular) with a unit
//! surface normal in place of the gradient, and no gradient gate.

use glint_lobe::Geometry;

use crate::math::Vec3;
use crate::shading::Shader;

impl Shader {
    /// Lit linear colour of a surface point of colour `base`, unit `normal` and unit
    /// `view` (towards the eye). Two-sided: a normal facing away from the viewer is
    /// flipped, so open surfaces and inner walls are lit from the side that is seen.
    #[inline]
    pub(crate) fn shade_surface(&self, base: [f32; 3], normal: Vec3, view: Vec3) -> [f32; 3] {
        let m = &self.material;
        if !m.shade {
            return base;
        }
        let mut n = normal;
        let mut n_dot_v = n.dot(view);
        if n_dot_v < 0.0 {
            n = -n;
            n_dot_v = -n_dot_v;
        }
        let (mut diffuse, mut specular) = (0.0f32, 0.0f32);
        for &(l, intensity) in &self.lights {
            let n_dot_l = n.dot(l);
            if n_dot_l > 0.0 {
                diffuse += intensity * n_dot_l;
                // Phong R·V = 2(N·L)(N·V) - L·V, Blinn N·H (glint_lobe::Geometry::cos
                // for unit vectors).
                let c = match self.geometry {
                    Geometry::Phong => 2.0 * n_dot_l * n_dot_v - l.dot(view),
                    Geometry::Blinn => n.dot((l + view).normalize_or_zero()),
                };
                specular += intensity * self.specular.eval(c);
            }
        }
        let lit = m.ambient + m.diffuse * diffuse;
        let spec = m.specular * specular;
        base.map(|c| c * lit + spec)
    }
}

#[cfg(test)]
mod tests {
    use glint_lobe::LobeKind;

    use super::*;
    use crate::tf::Material;

    #[test]
    fn surface_shading_matches_glint_lobe_geometry_and_is_two_sided() {
        let l = Vec3::new(0.3, 0.2, 0.9).normalize_or_zero();
        let v = Vec3::new(-0.1, 0.1, 1.0).normalize_or_zero();
        let n = Vec3::new(0.1, 0.0, 1.0).normalize_or_zero();
        let m = Material::default();
        for geometry in [Geometry::Phong, Geometry::Blinn] {
            let mut shader =
                Shader::new(LobeKind::Exact, 20.0, 4, geometry, m, vec![], 0.0).unwrap();
            shader.lights = vec![(l, 1.0)];
            let c = geometry.cos(n.to_array(), l.to_array(), v.to_array());
            let want = m.ambient + m.diffuse * n.dot(l) + m.specular * c.max(0.0).powf(20.0);
            let got = shader.shade_surface([1.0; 3], n, v);
            assert!(
                (got[0] - want).abs() < 1e-5,
                "{geometry}: {got:?} vs {want}"
            );
            // The back face seen from the front is lit like the front.
            assert_eq!(shader.shade_surface([1.0; 3], -n, v), got);
        }
    }
}
