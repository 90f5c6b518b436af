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
                crate::film::write::remove_writes_in_flight();
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
