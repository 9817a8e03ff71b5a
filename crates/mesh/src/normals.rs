//! Vertex normals of triangle meshes.

/// Area-weighted unit vertex normals of a triangle mesh (the cross product of two
/// edges is twice the area times the unit normal, so summing them weights by area).
/// Vertices of degenerate triangles only get a zero normal.
///
/// ```
/// // One triangle in the xy plane, counter-clockwise seen from +z.
/// let n = glint_mesh::vertex_normals(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], &[[0, 1, 2]]);
/// assert_eq!(n, vec![[0.0, 0.0, 1.0]; 3]);
/// ```
pub fn vertex_normals(positions: &[[f32; 3]], triangles: &[[u32; 3]]) -> Vec<[f32; 3]> {
    let mut normals = vec![[0.0f32; 3]; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let n = cross(sub(b, a), sub(c, a));
        for &i in t {
            let s = &mut normals[i as usize];
            *s = [s[0] + n[0], s[1] + n[1], s[2] + n[2]];
        }
    }
    normals.into_iter().map(normalize_or_zero).collect()
}

fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// The unit vector along `v`, or zero for a zero or non-finite vector (the same
/// operations as glint-core's `Vec3::normalize_or_zero`, so the renderer's normals are
/// bit for bit what it computed before they moved here).
fn normalize_or_zero(v: [f32; 3]) -> [f32; 3] {
    let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if len.is_finite() && len > 0.0 {
        let s = 1.0 / len;
        [v[0] * s, v[1] * s, v[2] * s]
    } else {
        [0.0; 3]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normals_weight_faces_by_area_and_skip_degenerate_ones() {
        // Two triangles sharing vertex 0: one in the xy plane (normal +z, edge cross
        // product of length 1) and one in the xz plane (normal +y, length 4).
        let p = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 2.0],
            [2.0, 0.0, 0.0],
        ];
        let n = vertex_normals(&p, &[[0, 1, 2], [0, 3, 4]]);
        // Vertex 0 sums both: (0, 0, 1) + (0, 4, 0).
        let want = normalize_or_zero([0.0, 4.0, 1.0]);
        assert_eq!(n[0], want);
        assert_eq!(n[1], [0.0, 0.0, 1.0]);
        assert_eq!(n[3], [0.0, 1.0, 0.0]);
        // A degenerate triangle contributes nothing.
        let n = vertex_normals(&[[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]], &[[0, 1, 2]]);
        assert_eq!(n, vec![[0.0; 3]; 3]);
    }
}
