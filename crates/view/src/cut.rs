//! The crop box and clip planes drawn over the image: before every frame of a scene
//! that cuts (clip planes or a crop box, split off) the server sends where the box's
//! corners and each plane's outline lie on that frame ([`ServerMessage::Cut`]),
//! projected with the frame's own camera as the marks of picking are
//! ([`glint_render::image_point`]): interactive frames carry no scene, so the page
//! could not project them itself. A plane's outline is where it crosses the
//! volume's bounds; its handle is the outline's centre and a point 15% of the
//! bounds' diagonal along the normal (towards the kept side). The crop box has a
//! handle on each of its six faces, drawn the same way: the face's centre and a
//! point as far along its outward normal, so that the page can turn the pointer's
//! travel on the image into the face's travel along its axis.

use glint_render::{image_point, ClipPlane, Scene};

use crate::protocol::{CutHandle, ServerMessage};

/// The world (mm) box of a volume's voxel centres: `[min, max]`.
pub(crate) type Bounds = [[f64; 3]; 2];

/// The world box of the voxel centres of a `dims` grid mapped by `to_world`
/// (continuous voxel index to world mm).
pub(crate) fn bounds(dims: [usize; 3], to_world: impl Fn([f64; 3]) -> [f64; 3]) -> Bounds {
    let mut out = [[f64::INFINITY; 3], [f64::NEG_INFINITY; 3]];
    for corner in corners([[0.0; 3], dims.map(|d| d.saturating_sub(1) as f64)]) {
        let w = to_world(corner);
        for a in 0..3 {
            out[0][a] = out[0][a].min(w[a]);
            out[1][a] = out[1][a].max(w[a]);
        }
    }
    out
}

/// The 8 corners of a box, corner `c` taking `max` along axis `a` where bit `a` of
/// `c` is set (the order the page draws the edges in).
fn corners(b: Bounds) -> [[f64; 3]; 8] {
    std::array::from_fn(|c| std::array::from_fn(|a| b[c >> a & 1][a]))
}

/// The 12 edges of a box as pairs of corner numbers ([`corners`]): the corners that
/// differ in one bit.
const EDGES: [(usize, usize); 12] = [
    (0, 1),
    (2, 3),
    (4, 5),
    (6, 7),
    (0, 2),
    (1, 3),
    (4, 6),
    (5, 7),
    (0, 4),
    (1, 5),
    (2, 6),
    (3, 7),
];

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Where `plane` crosses box `b`: the polygon's corners in order around it (world
/// mm), empty when it misses the box. Written here: a plane-box section is a dozen
/// lines and the workspace's geometry crates (glam) have none.
pub(crate) fn section(plane: &ClipPlane, b: Bounds) -> Vec<[f64; 3]> {
    let len = dot(plane.normal, plane.normal).sqrt();
    if len < 1e-12 {
        return Vec::new();
    }
    let n = plane.normal.map(|x| x / len);
    let c = corners(b);
    let d = c.map(|p| dot(n, p) - dot(n, plane.point));
    let mut points: Vec<[f64; 3]> = Vec::new();
    for (i, j) in EDGES {
        if (d[i] < 0.0) != (d[j] < 0.0) {
            let t = d[i] / (d[i] - d[j]);
            let p: [f64; 3] = std::array::from_fn(|a| c[i][a] + t * (c[j][a] - c[i][a]));
            // A corner on the plane is met by several edges: once is enough.
            if !points
                .iter()
                .any(|q| (0..3).all(|a| (q[a] - p[a]).abs() < 1e-9))
            {
                points.push(p);
            }
        }
    }
    if points.len() < 3 {
        return Vec::new();
    }
    let k = points.len() as f64;
    let centre: [f64; 3] = std::array::from_fn(|a| points.iter().map(|p| p[a]).sum::<f64>() / k);
    // Any direction in the plane, and the one perpendicular to it: the angle around
    // the centre orders the corners.
    let helper = if n[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let u = cross(n, helper);
    let v = cross(n, u);
    let angle = |p: &[f64; 3]| {
        let r = std::array::from_fn(|a| p[a] - centre[a]);
        dot(r, v).atan2(dot(r, u))
    };
    points.sort_by(|p, q| angle(p).total_cmp(&angle(q)));
    points
}

/// What the page draws for the frame of update `seq` rendered as `frame` (its
/// resolved scene, camera derived) of a volume of `bounds`: `None` when the scene
/// cuts nothing.
pub(crate) fn projected(frame: &Scene, seq: u32, bounds: Bounds) -> Option<ServerMessage> {
    if frame.clip.is_empty() && frame.crop.is_none() {
        return None;
    }
    let [w, h] = frame.size.map(f64::from);
    let onto = |p: [f64; 3]| image_point(frame, p).map(|[x, y]| [x / w, y / h]);
    let diagonal = (0..3)
        .map(|a| (bounds[1][a] - bounds[0][a]).powi(2))
        .sum::<f64>()
        .sqrt();
    let planes = frame
        .clip
        .iter()
        .map(|plane| {
            let outline = section(plane, bounds);
            let k = outline.len().max(1) as f64;
            let centre: [f64; 3] = if outline.is_empty() {
                plane.point
            } else {
                std::array::from_fn(|a| outline.iter().map(|p| p[a]).sum::<f64>() / k)
            };
            let len = dot(plane.normal, plane.normal).sqrt().max(1e-12);
            let tip = std::array::from_fn(|a| centre[a] + 0.15 * diagonal * plane.normal[a] / len);
            crate::protocol::CutPlane {
                outline: outline.into_iter().map(onto).collect(),
                handle: [onto(centre), onto(tip)],
            }
        })
        .collect();
    let crop = frame
        .crop
        .map(|c| corners([c.min, c.max]).map(onto).to_vec());
    let faces = frame.crop.map(|c| {
        face_handles([c.min, c.max], 0.15 * diagonal)
            .into_iter()
            .map(|[centre, tip]| CutHandle {
                handle: [onto(centre), onto(tip)],
            })
            .collect()
    });
    Some(ServerMessage::Cut {
        seq,
        crop,
        faces,
        planes,
    })
}

/// The handles of box `b`'s six faces (x min, x max, y min, ..., z max): each face's
/// centre and the point `length` mm from it along the face's outward normal.
pub(crate) fn face_handles(b: Bounds, length: f64) -> [[[f64; 3]; 2]; 6] {
    std::array::from_fn(|f| {
        let (axis, side) = (f / 2, f % 2);
        let mut centre: [f64; 3] = std::array::from_fn(|a| (b[0][a] + b[1][a]) / 2.0);
        centre[axis] = b[side][axis];
        let mut tip = centre;
        tip[axis] += if side == 0 { -length } else { length };
        [centre, tip]
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const CUBE: Bounds = [[0.0; 3], [10.0; 3]];

    #[test]
    fn an_axis_plane_cuts_a_square_and_a_slanted_one_a_hexagon() {
        let across = ClipPlane {
            point: [0.0, 0.0, 4.0],
            normal: [0.0, 0.0, -3.0],
        };
        let square = section(&across, CUBE);
        assert_eq!(square.len(), 4, "{square:?}");
        assert!(square.iter().all(|p| p[2] == 4.0));
        // In order around: consecutive corners share an x or a y.
        for (i, p) in square.iter().enumerate() {
            let q = square[(i + 1) % 4];
            assert!(p[0] == q[0] || p[1] == q[1], "{square:?}");
        }
        let slanted = ClipPlane {
            point: [5.0; 3],
            normal: [1.0; 3],
        };
        let hexagon = section(&slanted, CUBE);
        assert_eq!(hexagon.len(), 6, "{hexagon:?}");
        for p in &hexagon {
            assert!((p.iter().sum::<f64>() - 15.0).abs() < 1e-9, "{p:?}");
        }
        let outside = ClipPlane {
            point: [0.0, 0.0, 20.0],
            normal: [0.0, 0.0, 1.0],
        };
        assert!(section(&outside, CUBE).is_empty());
    }

    #[test]
    fn face_handles_sit_on_the_face_centres_and_point_outwards() {
        let b = [[0.0, 2.0, 4.0], [10.0, 6.0, 8.0]];
        let h = face_handles(b, 3.0);
        assert_eq!(h[0], [[0.0, 4.0, 6.0], [-3.0, 4.0, 6.0]]);
        assert_eq!(h[1], [[10.0, 4.0, 6.0], [13.0, 4.0, 6.0]]);
        assert_eq!(h[2], [[5.0, 2.0, 6.0], [5.0, -1.0, 6.0]]);
        assert_eq!(h[3], [[5.0, 6.0, 6.0], [5.0, 9.0, 6.0]]);
        assert_eq!(h[4], [[5.0, 4.0, 4.0], [5.0, 4.0, 1.0]]);
        assert_eq!(h[5], [[5.0, 4.0, 8.0], [5.0, 4.0, 11.0]]);
    }

    #[test]
    fn bounds_are_the_voxel_centres_box() {
        let b = bounds([3, 4, 5], |p| [2.0 * p[0] + 1.0, -p[1], p[2]]);
        assert_eq!(b, [[1.0, -3.0, 0.0], [5.0, 0.0, 4.0]]);
    }
}
