//! Long-running library work (scene loads, BVH builds) announces itself here, so that a
//! front end can show it: the `vkvcm` binary installs an [`Observer`] that draws a
//! progress line (src/cli/progress.rs). The library itself prints nothing; without an
//! observer an [`Activity`] is an empty handle and costs nothing.

use std::sync::OnceLock;

/// Receives the process's activities (installed once, by the front end).
pub trait Observer: Send + Sync {
    /// An activity began. `what` says what it is, e.g. "building the BVH (4194304
    /// primitives)"; `total` is its amount of work in the units of [`Tracker::advance`]
    /// (`None`: unknown). The activity ends when the returned tracker is dropped.
    fn begin(&self, what: String, total: Option<u64>) -> Box<dyn Tracker>;
}

/// The observer's handle on one running activity.
pub trait Tracker: Send + Sync {
    /// `units` more of the work are done (called from any thread).
    fn advance(&self, units: u64);
}

static OBSERVER: OnceLock<Box<dyn Observer>> = OnceLock::new();

/// Installs the process's observer; `false` if one already was (`observer` is dropped).
pub fn set_observer(observer: Box<dyn Observer>) -> bool {
    OBSERVER.set(observer).is_ok()
}

/// A running activity, reported to the observer if there is one; it ends when dropped.
pub struct Activity(Option<Box<dyn Tracker>>);

impl Activity {
    /// Begins an activity. `what` is called only when an observer is installed.
    pub fn begin(what: impl FnOnce() -> String, total: Option<u64>) -> Activity {
        Activity(OBSERVER.get().map(|o| o.begin(what(), total)))
    }

    /// `units` more of the work are done.
    pub fn advance(&self, units: u64) {
        if let Some(t) = &self.0 {
            t.advance(units);
        }
    }
}
