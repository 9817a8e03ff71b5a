//! Time spent inside a reader (the gzip inflater), readable after the reader has been
//! boxed into a `dyn Read` chain: `glint render --timings` reports inflating apart from
//! parsing (issue 12).

use std::io::Read;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Accumulated time of the readers made by [`Clock::timed`] (shared, so the clock
/// outlives a reader moved into a `Box<dyn Read>`).
#[derive(Clone)]
pub(crate) struct Clock {
    nanos: Arc<AtomicU64>,
    used: Arc<std::sync::atomic::AtomicBool>,
    /// The time source: `Instant::now`, or a fake one in tests.
    now: fn() -> Instant,
}

impl Default for Clock {
    fn default() -> Self {
        Clock {
            nanos: Arc::default(),
            used: Arc::default(),
            now: Instant::now,
        }
    }
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
        let start = (self.clock.now)();
        let r = self.inner.read(buf);
        let spent = (self.clock.now)().saturating_duration_since(start);
        let ns = u64::try_from(spent.as_nanos()).unwrap_or(u64::MAX);
        self.clock.nanos.fetch_add(ns, Ordering::Relaxed);
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell;

    thread_local! {
        /// Calls of the fake time source on this thread.
        static TICKS: Cell<u32> = const { Cell::new(0) };
    }

    /// A fake time source: 1 ms later at every call (so a read, which asks twice,
    /// takes exactly 1 ms); no wall time is involved.
    fn fake_now() -> Instant {
        static BASE: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();
        let t = TICKS.with(|t| {
            t.set(t.get() + 1);
            t.get()
        });
        *BASE.get_or_init(Instant::now) + Duration::from_millis(u64::from(t))
    }

    /// A reader of one byte a call.
    struct OneByte;
    impl Read for OneByte {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            buf[0] = 1;
            Ok(1)
        }
    }

    #[test]
    fn time_inside_reads_is_counted_and_unused_clocks_say_none() {
        let clock = Clock {
            now: fake_now,
            ..Clock::default()
        };
        assert_eq!(clock.spent(), None);
        let mut r: Box<dyn Read> = Box::new(clock.timed(OneByte));
        let mut b = [0u8; 4];
        for _ in 0..3 {
            r.read_exact(&mut b[..1]).unwrap();
        }
        drop(r);
        // Three reads of 1 fake millisecond each; the time between reads is not counted
        // (the source is not asked there).
        assert_eq!(clock.spent(), Some(Duration::from_millis(3)));
    }
}
