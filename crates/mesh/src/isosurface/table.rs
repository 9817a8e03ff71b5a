//! The marching-cubes case table, built at first use from the cube's topology rather
//! than typed in (Lorensen and Cline 1987 give 15 cases up to symmetry; the 256
//! entries follow from them).
//!
//! Hand-built rather than taken from a crate: the table must resolve the ambiguous
//! faces by a rule that only depends on the face's four corners, which is what makes
//! the surface watertight (Montani et al., "A modified look-up table for implicit
//! disambiguation of marching cubes", 1994: separate the inside corners). Deriving
//! it makes that rule explicit and testable.
//!
//! Corner `c` of a cell sits at offset `(c & 1, c >> 1 & 1, c >> 2 & 1)`. A corner is
//! inside when its value is at least the iso value.

use std::sync::OnceLock;

/// The 12 cell edges as corner pairs, x edges first, then y, then z; the first
/// corner is the one at the lower coordinate.
pub(crate) const EDGES: [(u8, u8); 12] = edges();

const fn edges() -> [(u8, u8); 12] {
    let mut out = [(0u8, 0u8); 12];
    let mut n = 0;
    let mut axis = 0;
    while axis < 3 {
        let mut c = 0u8;
        while c < 8 {
            if c & (1 << axis) == 0 {
                out[n] = (c, c | (1 << axis));
                n += 1;
            }
            c += 1;
        }
        axis += 1;
    }
    out
}

/// Triangles per case, as cell-edge indices, counter-clockwise seen from the outside
/// (the side of lower values).
pub(crate) struct Table {
    /// Per case: start and count in `triangles`.
    pub cases: [(u16, u8); 256],
    pub triangles: Vec<[u8; 3]>,
}

/// The table, built once.
pub(crate) fn table() -> &'static Table {
    static TABLE: OnceLock<Table> = OnceLock::new();
    TABLE.get_or_init(build)
}

fn corner_pos(c: u8) -> [f32; 3] {
    [(c & 1) as f32, (c >> 1 & 1) as f32, (c >> 2 & 1) as f32]
}

fn edge_of(a: u8, b: u8) -> usize {
    EDGES
        .iter()
        .position(|&(p, q)| (p, q) == (a, b) || (p, q) == (b, a))
        .expect("adjacent corners")
}

/// The four corners of each face in cyclic order.
fn faces() -> [[u8; 4]; 6] {
    let mut out = [[0u8; 4]; 6];
    for axis in 0..3 {
        let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
        for side in 0..2u8 {
            let at = |i: u8, j: u8| side << axis | i << b | j << c;
            out[axis * 2 + side as usize] = [at(0, 0), at(1, 0), at(1, 1), at(0, 1)];
        }
    }
    out
}

fn build() -> Table {
    let mut cases = [(0u16, 0u8); 256];
    let mut triangles = Vec::new();
    for (mask, case) in cases.iter_mut().enumerate() {
        let start = triangles.len();
        for ring in loops(mask as u8) {
            triangles.extend(triangulate(&ring));
        }
        *case = (start as u16, (triangles.len() - start) as u8);
    }
    Table { cases, triangles }
}

/// The closed loops of crossed edges of case `mask`, oriented counter-clockwise seen
/// from outside.
pub(crate) fn loops(mask: u8) -> Vec<Vec<u8>> {
    let inside = |c: u8| mask >> c & 1 == 1;
    // Each crossed edge lies on two faces and gets one neighbour on each.
    let mut next: [Vec<u8>; 12] = Default::default();
    let mut link = |a: usize, b: usize| {
        next[a].push(b as u8);
        next[b].push(a as u8);
    };
    for q in faces() {
        let e: [usize; 4] = std::array::from_fn(|i| edge_of(q[i], q[(i + 1) % 4]));
        let crossed: Vec<usize> = (0..4)
            .filter(|&i| inside(q[i]) != inside(q[(i + 1) % 4]))
            .collect();
        match crossed.len() {
            2 => link(e[crossed[0]], e[crossed[1]]),
            // Ambiguous face: cut each inside corner off on its own.
            4 => (0..4)
                .filter(|&i| inside(q[i]))
                .for_each(|i| link(e[(i + 3) % 4], e[i])),
            _ => {}
        }
    }
    let mut seen = [false; 12];
    let mut out = Vec::new();
    for start in 0..12 {
        if seen[start] || next[start].is_empty() {
            continue;
        }
        let (mut ring, mut prev, mut cur) = (vec![], usize::MAX, start);
        loop {
            seen[cur] = true;
            ring.push(cur as u8);
            let n = next[cur]
                .iter()
                .map(|&x| x as usize)
                .find(|&x| x != prev && !seen[x]);
            match n {
                Some(n) => (prev, cur) = (cur, n),
                None => break,
            }
        }
        orient(&mut ring, inside);
        out.push(ring);
    }
    out
}

/// Reverses `ring` unless its area vector (from edge midpoints) points from the
/// inside corners to the outside ones.
fn orient(ring: &mut [u8], inside: impl Fn(u8) -> bool) {
    let mid = |e: u8| {
        let (a, b) = EDGES[e as usize];
        let (p, q) = (corner_pos(a), corner_pos(b));
        [0, 1, 2].map(|i| 0.5 * (p[i] + q[i]))
    };
    let mut area = [0.0f32; 3];
    let mut out_dir = [0.0f32; 3];
    for (k, &e) in ring.iter().enumerate() {
        let (p, q) = (mid(e), mid(ring[(k + 1) % ring.len()]));
        area[0] += p[1] * q[2] - p[2] * q[1];
        area[1] += p[2] * q[0] - p[0] * q[2];
        area[2] += p[0] * q[1] - p[1] * q[0];
        let (a, b) = EDGES[e as usize];
        let (i, o) = if inside(a) { (a, b) } else { (b, a) };
        let (pi, po) = (corner_pos(i), corner_pos(o));
        (0..3).for_each(|d| out_dir[d] += po[d] - pi[d]);
    }
    if (0..3).map(|d| area[d] * out_dir[d]).sum::<f32>() < 0.0 {
        ring.reverse();
    }
}

/// Whether cell edges `a` and `b` lie on a common face.
fn share_face(a: u8, b: u8) -> bool {
    let (p, q) = (EDGES[a as usize], EDGES[b as usize]);
    let corners = [p.0, p.1, q.0, q.1];
    (0..3).any(|axis| {
        corners
            .iter()
            .all(|&c| (c >> axis & 1) == (corners[0] >> axis & 1))
    })
}

/// A fan over `ring` from an apex whose diagonals leave the cell's faces: a
/// diagonal on a face could meet the neighbouring cell's diagonal there, and the
/// edge would then have four triangles. Every loop of the table has such an apex
/// (tested).
fn triangulate(ring: &[u8]) -> Vec<[u8; 3]> {
    let n = ring.len();
    let apex = (0..n)
        .find(|&a| (2..n - 1).all(|d| !share_face(ring[a], ring[(a + d) % n])))
        .expect("every marching-cubes loop has an apex with interior diagonals");
    (1..n - 1)
        .map(|d| [ring[apex], ring[(apex + d) % n], ring[(apex + d + 1) % n]])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_case_has_closed_loops_and_the_table_matches_lorensen_counts() {
        let t = table();
        assert_eq!(t.cases[0].1, 0);
        assert_eq!(t.cases[255].1, 0);
        for mask in 0..=255u8 {
            // Every crossed edge is on exactly one loop.
            let crossed = EDGES
                .iter()
                .filter(|&&(a, b)| (mask >> a & 1) != (mask >> b & 1))
                .count();
            let on_loops: usize = loops(mask).iter().map(|l| l.len()).sum();
            assert_eq!(on_loops, crossed, "case {mask:#010b}");
        }
        // One inside corner: a single triangle (Lorensen and Cline's case 1); a cell
        // cut in half along a face (case 8): two triangles.
        assert_eq!(t.cases[0b0000_0001].1, 1);
        assert_eq!(t.cases[0b0000_1111].1, 2);
    }

    #[test]
    fn single_corner_triangle_faces_away_from_the_inside_corner() {
        // Corner 0 inside: the triangle's normal points towards +x+y+z (outside).
        let t = table();
        let (s, _) = t.cases[1];
        let tri = t.triangles[s as usize];
        let p = tri.map(|e| {
            let (a, b) = EDGES[e as usize];
            let (p, q) = (corner_pos(a), corner_pos(b));
            [0, 1, 2].map(|i| 0.5 * (p[i] + q[i]))
        });
        let u = [0, 1, 2].map(|i| p[1][i] - p[0][i]);
        let v = [0, 1, 2].map(|i| p[2][i] - p[0][i]);
        let n = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        assert!(n.iter().all(|&x| x > 0.0), "{n:?}");
    }
}
