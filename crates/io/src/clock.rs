//! Time spent inside a reader (the gzip inflater), readable after the reader has been
//! boxed into a `dyn Read` chain: `glint render --timings` reports inflating apart from
//! parsing (issue 12).

use std::io::Read;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Accumulated time of the readers made by [`Clock::timed`] (shared, so the clock
/// outlives a reader moved into a `Box<dyn Read>`).
#[derive(Clone, Default)]
pub(crate) struct Clock {
    nanos: Arc<AtomicU64>,
    used: Arc<std::sync::atomic::AtomicBool>,
}

impl Clock {
    /// `inner`, with the time of each `read` call added to this clock.
    pub(crate) fn timed<R: Read>(&self, inner: R) -> Timed<R> {
        self.used.store(true, Ordering::Relaxed);
        Timed {
            inner,
            clock: self.clone(),
        }
    }

    /// The time spent so far, `None` if no reader was timed.
    pub(crate) fn spent(&self) -> Option<Duration> {
        self.used
            .load(Ordering::Relaxed)
            .then(|| Duration::from_nanos(self.nanos.load(Ordering::Relaxed)))
    }
}

/// A reader whose `read` calls are timed by a [`Clock`].
pub(crate) struct Timed<R> {
    inner: R,
    clock: Clock,
}

impl<R: Read> Read for Timed<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let start = Instant::now();
        let r = self.inner.read(buf);
        let ns = u64::try_from(start.elapsed().as_nanos()).unwrap_or(u64::MAX);
        self.clock.nanos.fetch_add(ns, Ordering::Relaxed);
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A reader that takes a known time per call.
    struct Slow;
    impl Read for Slow {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            std::thread::sleep(Duration::from_millis(5));
            buf[0] = 1;
            Ok(1)
        }
    }

    #[test]
    fn time_inside_reads_is_counted_and_unused_clocks_say_none() {
        let clock = Clock::default();
        assert_eq!(clock.spent(), None);
        let mut r: Box<dyn Read> = Box::new(clock.timed(Slow));
        let mut b = [0u8; 4];
        for _ in 0..3 {
            r.read_exact(&mut b[..1]).unwrap();
        }
        drop(r);
        assert!(clock.spent().unwrap() >= Duration::from_millis(15));
    }
}
