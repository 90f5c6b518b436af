//! Every integration test runs in one process, on as many test threads as
//! there are cores, so a test that measures time could share the cores with
//! a render and see its deadlines slip. Two guards keep them apart:
//!
//! - [`serial()`] for tests that measure time (a time limit, how fast an
//!   interruption or a signal takes effect, checkpoints appearing): it
//!   waits until no other guarded test runs, and holds the others off.
//! - [`heavy()`] for tests that keep the cores busy (renders, the `tracer`
//!   binary, large BVH builds, many samples): any number of them run
//!   together, but never beside a [`serial()`] test.
//!
//! Take the guard first thing in the test, keep it to the end
//! (`let _guard = common::heavy();`), and take one guard at most: a test
//! that takes a second one while holding the first can deadlock behind a
//! waiting [`serial()`] test. Tests that take neither are cheap (parsing,
//! small writes) and may run beside anything.

use std::sync::{PoisonError, RwLock, RwLockReadGuard, RwLockWriteGuard};

static CORES: RwLock<()> = RwLock::new(());

/// Runs the calling test alone among the guarded tests; for tests that
/// measure time.
pub fn serial() -> RwLockWriteGuard<'static, ()> {
    // A test that failed while holding the lock leaves it poisoned; the
    // lock guards no data, so the others carry on.
    CORES.write().unwrap_or_else(PoisonError::into_inner)
}

/// Keeps [`serial()`] tests from running beside the calling test; for
/// tests that keep the cores busy.
pub fn heavy() -> RwLockReadGuard<'static, ()> {
    CORES.read().unwrap_or_else(PoisonError::into_inner)
}
