//! A progress spinner on stderr for work of unknown length (reading a volume, building
//! the field): shown only once the work has taken a second, never when stderr is not
//! a terminal or the command is quiet, cleared when the work ends.

use std::io::IsTerminal;
use std::sync::mpsc::{self, RecvTimeoutError, Sender};
use std::thread::JoinHandle;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// How long work runs before its spinner shows.
const DELAY: Duration = Duration::from_secs(1);

/// A spinner running while it lives; dropping it clears it.
pub(crate) struct Spinner {
    bar: ProgressBar,
    stop: Option<Sender<()>>,
    shower: Option<JoinHandle<()>>,
}

impl Spinner {
    /// A spinner saying `what` (e.g. "reading head.nii"), drawn after [`DELAY`] unless
    /// `quiet` or stderr is not a terminal.
    pub(crate) fn start(what: String, quiet: bool) -> Spinner {
        let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden());
        let (tx, rx) = mpsc::channel::<()>();
        let shower = (!quiet && std::io::stderr().is_terminal()).then(|| {
            let bar = bar.clone();
            std::thread::spawn(move || {
                if let Err(RecvTimeoutError::Timeout) = rx.recv_timeout(DELAY) {
                    bar.set_style(
                        ProgressStyle::with_template("{spinner} {msg} {elapsed}")
                            .expect("static template"),
                    );
                    bar.set_message(what);
                    bar.set_draw_target(ProgressDrawTarget::stderr());
                    bar.enable_steady_tick(Duration::from_millis(120));
                }
            })
        });
        Spinner {
            bar,
            stop: Some(tx),
            shower,
        }
    }
}

impl Drop for Spinner {
    fn drop(&mut self) {
        // Closing the channel wakes the thread before its delay if the work was short.
        drop(self.stop.take());
        if let Some(t) = self.shower.take() {
            let _ = t.join();
        }
        self.bar.finish_and_clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Quiet (and in tests, where stderr is not a terminal or is captured), the
    /// spinner starts no thread and draws nothing.
    #[test]
    fn a_quiet_spinner_draws_nothing() {
        let s = Spinner::start("reading".into(), true);
        assert!(s.shower.is_none());
        assert!(s.bar.is_hidden());
    }
}
