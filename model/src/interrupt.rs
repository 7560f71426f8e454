//! A question long work asks now and then: should it stop? (Ctrl-C from
//! Python, whose signal handler runs only when native code asks for it.)
//!
//! The estimator asks it around every pass and every 32768 samples of its
//! own data walks, and a frame's columns ask it every 32768 rows while they
//! are validated: that is how Python's Ctrl-C reaches a running estimate.

/// A question the estimator asks around its passes and during its data
/// walks: should it stop? Once answered yes, it stays yes (a signal handler
/// answers only once).
#[derive(Clone)]
pub struct Interrupt {
    ask: std::sync::Arc<dyn Fn() -> bool + Send + Sync>,
    stopped: std::sync::Arc<std::sync::atomic::AtomicBool>,
}

impl Interrupt {
    /// An interrupt that asks `requested`.
    pub fn new(requested: impl Fn() -> bool + Send + Sync + 'static) -> Interrupt {
        Interrupt {
            ask: std::sync::Arc::new(requested),
            stopped: std::sync::Arc::default(),
        }
    }

    /// Whether the estimate should stop now.
    pub fn requested(&self) -> bool {
        use std::sync::atomic::Ordering;
        if self.stopped.load(Ordering::Relaxed) {
            return true;
        }
        let stop = (self.ask)();
        if stop {
            self.stopped.store(true, Ordering::Relaxed);
        }
        stop
    }
}

impl std::fmt::Debug for Interrupt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Interrupt")
    }
}
