//! Picking and measuring in the viewer: a click's point ([`ClientMessage::Pick`]),
//! picked by the client's own renderer ([`Renderer::pick`]), kept as a mark (two make
//! a ruler); every frame then comes with the marks projected by that frame's own
//! camera ([`ServerMessage::Marks`]), interactive frames included, whose resolved
//! camera the page never receives. Projecting on the server keeps one projection
//! ([`glint_render::image_point`], tested against picks) and leaves the page to draw.
//!
//! [`ClientMessage::Pick`]: crate::protocol::ClientMessage::Pick

use glint_render::{image_point, RenderError, Renderer, Scene};

use crate::protocol::ServerMessage;

/// Marks a client keeps at most: a point, or the two ends of a ruler.
pub const MAX_MARKS: usize = 2;

/// One client's marks, world mm.
#[derive(Clone, Debug, Default)]
pub(crate) struct Marks {
    points: Vec<[f64; 3]>,
}

impl Marks {
    /// Whether there are none.
    pub(crate) fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Removes them.
    pub(crate) fn clear(&mut self) {
        self.points.clear();
    }

    /// The ruler's length, mm, when there are two marks.
    fn distance(&self) -> Option<f64> {
        match self.points.as_slice() {
            [a, b] => Some((0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()),
            _ => None,
        }
    }

    /// Picks pixel `(x, y)` of `scene`'s full-resolution image and marks the point
    /// (a third mark starts again from one); the answer for the page.
    pub(crate) fn pick(
        &mut self,
        renderer: &mut Renderer,
        scene: &Scene,
        (x, y): (f64, f64),
    ) -> Result<ServerMessage, RenderError> {
        let pick = renderer.pick(scene, x, y)?;
        if let Some(p) = &pick {
            if self.points.len() >= MAX_MARKS {
                self.points.clear();
            }
            self.points.push(p.world_mm);
        }
        Ok(ServerMessage::Pick {
            pick: serde_json::to_value(&pick).expect("picks serialise"),
            marks: self.points.clone(),
            distance_mm: self.distance(),
        })
    }

    /// The marks on the frame of update `seq` rendered as `frame` (the resolved
    /// scene of the frame, its camera derived), as fractions of its size.
    pub(crate) fn projected(&self, frame: &Scene, seq: u32) -> ServerMessage {
        let [w, h] = frame.size.map(f64::from);
        ServerMessage::Marks {
            seq,
            points: self
                .points
                .iter()
                .map(|&p| image_point(frame, p).map(|[x, y]| [x / w, y / h]))
                .collect(),
            distance_mm: self.distance(),
        }
    }
}
