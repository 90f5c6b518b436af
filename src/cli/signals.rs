//! Ctrl-C and SIGTERM during a render: the first stops it within a tile's
//! work and lets it write what it has; a second exits at once.

use std::io::Write;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;

/// The exit status of a render stopped by Ctrl-C or SIGTERM, after it wrote
/// its image (128 + SIGINT, as shells report it).
pub const INTERRUPTED_EXIT: i32 = 130;

/// The first SIGINT or SIGTERM sets the flag (the render stops within a
/// tile's work and writes what it has); a second exits at once.
pub fn interrupt_flag() -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    let handler_flag = flag.clone();
    // Signals are counted apart from the flag, which closing the preview
    // window also sets: only a second *signal* exits at once.
    let signals = AtomicUsize::new(0);
    let installed = ctrlc::set_handler(move || {
        // ctrlc runs this on a thread of its own; a closed stderr must not
        // panic it (that would leave later signals unanswered).
        let say = |m: &str| {
            let _ = writeln!(std::io::stderr(), "\n{m}");
        };
        match signal_action(&signals) {
            SignalAction::ExitNow => {
                say("interrupted again: exiting without writing");
                tracer::film::write::remove_writes_in_flight();
                std::process::exit(INTERRUPTED_EXIT);
            }
            SignalAction::Stop => {
                handler_flag.store(true, Ordering::SeqCst);
                say("interrupted: finishing the tiles in flight and writing the image (Ctrl-C again to quit at once)");
            }
        }
    });
    if let Err(e) = installed {
        eprintln!("warning: cannot catch Ctrl-C ({e}); an interrupted render will be lost");
    }
    flag
}

/// The exit status after a mapped scene cache entry vanished under the
/// render (SIGBUS): 128 + SIGBUS, as shells report a death by that signal.
pub const CACHE_VANISHED_EXIT: i32 = 128 + libc::SIGBUS;

/// Turns SIGBUS, which a truncated memory-mapped cache entry raises when
/// the render touches its lost pages, into a message and an orderly exit
/// instead of a crash. Images are only ever written whole (a temporary
/// file renamed into place), so the last checkpoint on disk stays intact.
pub fn report_vanished_cache_entries() {
    extern "C" fn on_sigbus(_: libc::c_int) {
        const MESSAGE: &[u8] = b"\nerror: a scene cache entry this render maps was truncated or replaced in place (SIGBUS); the last checkpoint written is intact. Render again (the entry is checked and rebuilt), or use --no-cache for a cache folder other machines write to.\n";
        // SAFETY: write(2) and _exit(2) are async-signal-safe, and MESSAGE
        // is a static buffer of the length given.
        unsafe {
            libc::write(2, MESSAGE.as_ptr().cast(), MESSAGE.len());
            libc::_exit(CACHE_VANISHED_EXIT);
        }
    }
    // SAFETY: the action is zeroed then filled in before use, and the
    // handler only makes async-signal-safe calls.
    unsafe {
        let mut action: libc::sigaction = std::mem::zeroed();
        action.sa_sigaction = on_sigbus as *const () as libc::sighandler_t;
        libc::sigemptyset(&mut action.sa_mask);
        libc::sigaction(libc::SIGBUS, &action, std::ptr::null_mut());
    }
}

#[derive(Debug, PartialEq, Eq)]
enum SignalAction {
    Stop,
    ExitNow,
}

/// The first signal stops the render; any later one exits at once.
fn signal_action(signals: &AtomicUsize) -> SignalAction {
    if signals.fetch_add(1, Ordering::SeqCst) == 0 {
        SignalAction::Stop
    } else {
        SignalAction::ExitNow
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_signal_stops_and_the_second_exits() {
        let signals = AtomicUsize::new(0);
        assert_eq!(signal_action(&signals), SignalAction::Stop);
        assert_eq!(signal_action(&signals), SignalAction::ExitNow);
        assert_eq!(signal_action(&signals), SignalAction::ExitNow);
    }
}
