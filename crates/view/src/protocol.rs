//! The viewer's wire protocol: JSON text messages for events, binary messages for
//! frames (a fixed header, then a JPEG or PNG).

use serde::{Deserialize, Serialize};

/// A message from the page.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum ClientMessage {
    /// Change scene fields (a partial scene: top-level fields replace the current
    /// ones; `camera`, `lobe` and `material` merge field by field). `seq` is echoed in
    /// the frame that shows it; `interactive` asks for a quick, reduced frame (while
    /// dragging), followed by a full one when the input stops.
    Update {
        /// The client's event number.
        seq: u32,
        /// A reduced frame now, a full one when the input stops.
        #[serde(default)]
        interactive: bool,
        /// The fields to change.
        #[serde(default)]
        scene: serde_json::Map<String, serde_json::Value>,
    },
    /// Show the chosen lobe alone, beside `exact`, or as a difference heat map.
    Split {
        /// The split mode.
        split: Split,
    },
    /// Send the full-resolution PNG and the resolved scene, for download.
    Save {},
    /// Pick the point pixel `(x, y)` of the full-resolution image shows (pixels from
    /// its top-left corner) and mark it: the first mark is a point, the second makes
    /// a ruler with the first, a third starts again. Answered by
    /// [`ServerMessage::Pick`]; every frame after it comes with
    /// [`ServerMessage::Marks`].
    Pick {
        /// Pixels from the image's left edge.
        x: f64,
        /// Pixels from the image's top edge.
        y: f64,
    },
    /// Remove the marks.
    Unmark {},
    /// Record a turntable of the current scene (as `glint render --turntable`
    /// renders it, at the scene's size) as a file sent to the page: answered by
    /// [`ServerMessage::Recording`] messages, then [`ServerMessage::Recorded`] and
    /// the file as a binary message.
    Record {
        /// Views round the scene (2..=360).
        frames: u32,
        /// `gif`, `webp` or (with ffmpeg) `mp4`.
        format: String,
    },
}

/// What a frame shows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Split {
    /// The scene's lobe.
    #[default]
    Off,
    /// `exact` on the left, the scene's lobe on the right.
    Side,
    /// The difference of the two in CIE luminance, as a heat map.
    Diff,
}

/// A message to the page.
// `Hello` is the large variant; it is built and sent once per connection, so boxing
// it would only add an allocation.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, Serialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum ServerMessage {
    /// Sent once on connection.
    Hello {
        /// The resolved starting scene.
        scene: serde_json::Value,
        /// Preset names.
        presets: Vec<&'static str>,
        /// Lobe names.
        lobes: Vec<&'static str>,
        /// View names.
        views: Vec<&'static str>,
        /// The environment maps `path` may name here: built in, and the fetched probes
        /// present ([`glint_render::available_environments`]).
        environments: Vec<&'static str>,
        /// The volume's value range (for the iso slider).
        range: [f32; 2],
        /// The labels present in the scene's label map, in value order (empty
        /// without one): the page's legend, toggled through `labels.hide`.
        labels: Vec<crate::labels::LabelInfo>,
        /// The pyramid level the frames come from (null: not a pyramid).
        level: Option<crate::levels::PyramidLevel>,
        /// The world (mm) box of the volume's voxel centres, `[min, max]` (null: a
        /// scene of meshes only): where the page's crop box and clip plane start.
        bounds: Option<[[f64; 3]; 2]>,
        /// The formats [`ClientMessage::Record`] may ask for: `gif`, `webp`, and
        /// `mp4` when `ffmpeg` is on the server's `PATH`.
        record: Vec<&'static str>,
    },
    /// How far the recording asked for by [`ClientMessage::Record`] is.
    Recording {
        /// Percent of its pixels rendered.
        percent: u32,
    },
    /// The recording is done: the next binary message is the file (not a frame).
    Recorded {
        /// The file's format (`gif`, `webp` or `mp4`: its extension).
        format: String,
        /// Frames in it.
        frames: u32,
        /// The file's size in bytes.
        bytes: usize,
    },
    /// The frames now come from another pyramid level (the finer one, read in the
    /// background, swapped in when the camera rests).
    Level {
        /// The level.
        level: crate::levels::PyramidLevel,
    },
    /// The volume's histogram, sent once after `hello` (not for a scene of meshes
    /// only): the page's transfer-function editor draws it.
    Histogram {
        /// The histogram.
        #[serde(flatten)]
        histogram: crate::histogram::Histogram,
    },
    /// The resolved scene a full frame was rendered from.
    Scene {
        /// The update it reflects.
        seq: u32,
        /// The scene.
        scene: serde_json::Value,
        /// The window and level of the transfer function the frame used (its own,
        /// `TransferFunction::window_level`: the scene's `window_level` when set),
        /// where the page's window/level drag starts; absent without one (surfaces).
        #[serde(skip_serializing_if = "Option::is_none")]
        window_level: Option<glint_render::WindowLevel>,
    },
    /// The answer to [`ClientMessage::Pick`].
    Pick {
        /// What the pixel shows (`glint_render::Pick` as JSON), null where it shows
        /// nothing (no mark is made then).
        pick: serde_json::Value,
        /// The marks now, world mm (at most two).
        marks: Vec<[f64; 3]>,
        /// The ruler's length, mm, when there are two marks.
        distance_mm: Option<f64>,
    },
    /// Where the marks lie on the frame that follows (sent before every frame while
    /// there are marks, and with no points after [`ClientMessage::Unmark`]): per mark,
    /// its position as fractions of the image's width and height from the top-left
    /// corner, projected with that frame's camera (null: behind the eye).
    Marks {
        /// The update the frame reflects.
        seq: u32,
        /// Per mark, `[x / width, y / height]`.
        points: Vec<Option<[f64; 2]>>,
        /// The ruler's length, mm, when there are two marks.
        distance_mm: Option<f64>,
    },
    /// Where the scene's crop box and clip planes lie on the frame that follows
    /// (sent before every frame of a scene that cuts, split off), as fractions of
    /// the image's width and height from the top-left corner, projected with that
    /// frame's camera (null: behind the eye).
    Cut {
        /// The update the frame reflects.
        seq: u32,
        /// The crop box's 8 corners, corner `c` at the box's max along axis `a`
        /// where bit `a` of `c` is set (null: no crop box).
        crop: Option<Vec<Option<[f64; 2]>>>,
        /// The crop box's 6 face handles, in the order x min, x max, y min, y max,
        /// z min, z max (null: no crop box).
        faces: Option<Vec<CutHandle>>,
        /// Per clip plane, in the scene's order.
        planes: Vec<CutPlane>,
    },
    /// A message was refused; the previous state stays.
    Error {
        /// One line for the user.
        message: String,
    },
}

/// A clip plane as [`ServerMessage::Cut`] draws it.
#[derive(Clone, Debug, Serialize)]
pub struct CutPlane {
    /// Where the plane crosses the volume's bounds, corners in order around.
    pub outline: Vec<Option<[f64; 2]>>,
    /// The handle: the outline's centre and a point along the normal (towards the
    /// side kept).
    pub handle: [Option<[f64; 2]>; 2],
}

/// A crop box face's handle as [`ServerMessage::Cut`] draws it: dragging it moves
/// the face along its axis.
#[derive(Clone, Debug, Serialize)]
pub struct CutHandle {
    /// The face's centre and a point outside the box along the face's outward
    /// normal, 15% of the volume bounds' diagonal away (the handle's world length):
    /// the pointer's travel along the line between them on the image gives the
    /// face's travel in mm.
    pub handle: [Option<[f64; 2]>; 2],
}

/// Size of [`FrameHeader`] on the wire.
pub const HEADER_BYTES: usize = 24;

/// The frame image's encoding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Format {
    /// Baseline JPEG.
    Jpeg = 0,
    /// PNG.
    Png = 1,
}

/// Why a frame was sent.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Purpose {
    /// Reduced resolution, while the user drags.
    Interactive = 0,
    /// Full resolution, when the input stops.
    Full = 1,
    /// Full-resolution PNG for download.
    Save = 2,
}

/// The header before every frame's image bytes: magic `GLNT`, then little-endian
/// `seq: u32, width: u32, height: u32, render_ms: f32`, format and purpose bytes, and
/// `samples: u16` (the path-traced samples per pixel the frame holds, 0 for the
/// `local` and `shadows` models).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameHeader {
    /// The last update the frame reflects.
    pub seq: u32,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Render time on the server, ms.
    pub render_ms: f32,
    /// Encoding.
    pub format: Format,
    /// Why it was sent.
    pub purpose: Purpose,
    /// Path-traced samples per pixel in the image (0: not path traced); saturates at
    /// `u16::MAX`.
    pub samples: u16,
}

impl FrameHeader {
    /// The header followed by `image`.
    pub fn encode(&self, image: &[u8]) -> Vec<u8> {
        let mut out = Vec::with_capacity(HEADER_BYTES + image.len());
        out.extend_from_slice(b"GLNT");
        out.extend_from_slice(&self.seq.to_le_bytes());
        out.extend_from_slice(&self.width.to_le_bytes());
        out.extend_from_slice(&self.height.to_le_bytes());
        out.extend_from_slice(&self.render_ms.to_le_bytes());
        out.extend_from_slice(&[self.format as u8, self.purpose as u8]);
        out.extend_from_slice(&self.samples.to_le_bytes());
        out.extend_from_slice(image);
        out
    }

    /// Splits a frame message into its header and image bytes.
    pub fn decode(bytes: &[u8]) -> Option<(FrameHeader, &[u8])> {
        if bytes.len() < HEADER_BYTES || &bytes[..4] != b"GLNT" {
            return None;
        }
        let u = |i: usize| u32::from_le_bytes(bytes[i..i + 4].try_into().unwrap());
        let format = match bytes[20] {
            0 => Format::Jpeg,
            1 => Format::Png,
            _ => return None,
        };
        let purpose = match bytes[21] {
            0 => Purpose::Interactive,
            1 => Purpose::Full,
            2 => Purpose::Save,
            _ => return None,
        };
        let header = FrameHeader {
            seq: u(4),
            width: u(8),
            height: u(12),
            render_ms: f32::from_bits(u(16)),
            format,
            purpose,
            samples: u16::from_le_bytes([bytes[22], bytes[23]]),
        };
        Some((header, &bytes[HEADER_BYTES..]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_round_trips() {
        let h = FrameHeader {
            seq: 7,
            width: 640,
            height: 480,
            render_ms: 12.5,
            format: Format::Png,
            purpose: Purpose::Save,
            samples: 300,
        };
        let bytes = h.encode(b"img");
        assert_eq!(bytes.len(), HEADER_BYTES + 3);
        assert_eq!(FrameHeader::decode(&bytes), Some((h, &b"img"[..])));
        assert_eq!(FrameHeader::decode(&bytes[..10]), None);
    }

    #[test]
    fn client_messages_parse_strictly() {
        let m: ClientMessage =
            serde_json::from_str(r#"{"type": "update", "seq": 3, "scene": {"step": 1}}"#).unwrap();
        assert!(matches!(
            m,
            ClientMessage::Update {
                seq: 3,
                interactive: false,
                ..
            }
        ));
        assert!(serde_json::from_str::<ClientMessage>(r#"{"type": "save", "x": 1}"#).is_err());
        assert!(serde_json::from_str::<ClientMessage>(r#"{"type": "delete"}"#).is_err());
    }
}
