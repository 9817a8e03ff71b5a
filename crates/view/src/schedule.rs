//! Which frame a client is owed next: the viewer's progressive logic, without the
//! transport. `glint view`'s WebSocket connections and the notebook viewer
//! (`glint.Viewer`, through [`crate::Session`]) both follow it.
//!
//! While the user drags, each input asks for a reduced ([`Purpose::Interactive`])
//! frame and puts the full frame off until the input has been quiet for the settle
//! time; then a [`Purpose::Full`] frame follows. A progressive (`path`) state keeps
//! asking for full frames while it holds still, each adding samples to the last
//! ([`next_samples`]) up to its goal; any input starts again from none.

use std::time::{Duration, Instant};

use crate::protocol::Purpose;

/// The sample count a progressive `path` frame renders to, having `done` of `goal`:
/// 1, 2, 4, 8, then 8 more at a time, so each refinement of a 512x512 frame takes a
/// bounded time and input is answered between two of them.
pub fn next_samples(done: u32, goal: u32) -> u32 {
    done.saturating_add(done.clamp(1, 8)).min(goal).max(1)
}

/// What a client is owed: the next frame, a save, the full frame due when the input
/// settles, and how far the current progressive state has refined.
#[derive(Clone, Debug)]
pub struct Schedule {
    /// The frame to render next, if any.
    wanted: Option<Purpose>,
    /// A full-resolution PNG was asked for.
    save: bool,
    /// When the full frame is due (`None`: no drag under way).
    settle: Option<Instant>,
    /// Samples per pixel the last full frame of the current state held (`path`).
    reached: u32,
}

impl Default for Schedule {
    /// A new client: a full frame first.
    fn default() -> Self {
        Schedule {
            wanted: Some(Purpose::Full),
            save: false,
            settle: None,
            reached: 0,
        }
    }
}

impl Schedule {
    /// The state changed: a reduced frame now and the full one `settle` after `now`
    /// when `interactive` (a drag), else a full frame now. Refinement starts again.
    pub fn input(&mut self, interactive: bool, now: Instant, settle: Duration) {
        self.reached = 0;
        if interactive {
            self.wanted = Some(Purpose::Interactive);
            self.settle = Some(now + settle);
        } else {
            self.wanted = Some(Purpose::Full);
            self.settle = None;
        }
    }

    /// A full-resolution PNG is wanted (rendered before any other frame).
    pub fn save(&mut self) {
        self.save = true;
    }

    /// When the drag's full frame is due (`None`: no drag under way).
    pub fn settle_at(&self) -> Option<Instant> {
        self.settle
    }

    /// The input has been quiet until `now`: when the settle time has passed, the
    /// full frame is owed. Returns whether it was.
    pub fn settled(&mut self, now: Instant) -> bool {
        match self.settle {
            Some(at) if at <= now => {
                self.settle = None;
                self.wanted = Some(Purpose::Full);
                true
            }
            _ => false,
        }
    }

    /// The frame to render next, if any (a save first), taken off the list.
    pub fn take(&mut self) -> Option<Purpose> {
        if self.save {
            self.save = false;
            Some(Purpose::Save)
        } else {
            self.wanted.take()
        }
    }

    /// Whether a frame is owed now.
    pub fn owes(&self) -> bool {
        self.save || self.wanted.is_some()
    }

    /// Whether the camera rests: no drag under way, no drag frame owed.
    pub fn resting(&self) -> bool {
        self.settle.is_none() && self.wanted != Some(Purpose::Interactive)
    }

    /// Starts the current state again from a full frame of no samples (e.g. another
    /// pyramid level was swapped in).
    pub fn restart(&mut self) {
        (self.wanted, self.reached) = (Some(Purpose::Full), 0);
    }

    /// Samples per pixel of the last full frame of the current state.
    pub fn reached(&self) -> u32 {
        self.reached
    }

    /// The sample count the next full frame renders to, for a progressive state
    /// refining to `goal` (`None`: not progressive, the scene's own count).
    pub fn samples_for(&self, goal: Option<u32>) -> Option<u32> {
        goal.map(|g| next_samples(self.reached, g))
    }

    /// A full frame of the current state holding `samples` arrived: a progressive
    /// state (refining to `goal`) still short of its goal asks for the next.
    pub fn full_done(&mut self, samples: u32, goal: Option<u32>) {
        self.reached = samples;
        if goal.is_some_and(|g| samples < g) {
            self.refine();
        }
    }

    /// A refinement was cancelled by input: its samples are gone, start again from
    /// none.
    pub fn cancelled(&mut self) {
        self.reached = 0;
        self.refine();
    }

    /// A full frame again when nothing else is owed (a `path` state refining).
    fn refine(&mut self) {
        if self.wanted.is_none() && self.settle.is_none() {
            self.wanted = Some(Purpose::Full);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_drag_gets_reduced_frames_then_one_full_frame_when_it_settles() {
        let (t0, settle) = (Instant::now(), Duration::from_millis(150));
        let mut s = Schedule::default();
        assert_eq!(s.take(), Some(Purpose::Full));
        assert_eq!(s.take(), None);
        s.input(true, t0, settle);
        assert!(!s.resting());
        assert_eq!(s.take(), Some(Purpose::Interactive));
        assert!(!s.settled(t0 + Duration::from_millis(100)));
        assert_eq!(s.take(), None);
        assert!(s.settled(t0 + settle));
        assert!(s.resting());
        assert_eq!(s.take(), Some(Purpose::Full));
        s.save();
        s.input(false, t0, settle);
        assert_eq!(
            (s.take(), s.take()),
            (Some(Purpose::Save), Some(Purpose::Full))
        );
    }

    #[test]
    fn a_progressive_state_refines_to_its_goal_and_input_restarts_it() {
        let (t0, settle) = (Instant::now(), Duration::from_millis(150));
        let mut s = Schedule::default();
        let mut counts = Vec::new();
        while let Some(p) = s.take() {
            assert_eq!(p, Purpose::Full);
            let n = s.samples_for(Some(20)).unwrap();
            counts.push(n);
            s.full_done(n, Some(20));
        }
        assert_eq!(counts, [1, 2, 4, 8, 16, 20]);
        s.input(true, t0, settle);
        assert_eq!(s.reached(), 0);
        assert_eq!(s.take(), Some(Purpose::Interactive));
        // A refinement finishing during a drag asks for nothing more.
        s.full_done(1, Some(20));
        assert_eq!(s.take(), None);
        assert!(s.settled(t0 + settle));
        assert_eq!(s.take(), Some(Purpose::Full));
        s.cancelled();
        assert_eq!(
            (s.take(), s.samples_for(Some(20))),
            (Some(Purpose::Full), Some(1))
        );
        assert_eq!(s.samples_for(None), None);
    }
}
