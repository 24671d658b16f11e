//! Ctrl-C as a request, not a kill: the first SIGINT (or SIGTERM) sets a flag that long
//! commands poll between units of work, so they can finish writing what is complete and leave
//! nothing half-written. A second one exits at once (every output is written by temp file and
//! rename, so even then no partial file is left behind).

use std::sync::Once;
use std::sync::atomic::{AtomicBool, Ordering};

static REQUESTED: AtomicBool = AtomicBool::new(false);
static INSTALL: Once = Once::new();

/// Installs the handler (idempotent). Failure to install is not fatal: the command then simply
/// cannot stop early.
pub fn install() {
    INSTALL.call_once(|| {
        let r = ctrlc::set_handler(|| {
            if REQUESTED.swap(true, Ordering::SeqCst) {
                eprintln!("\ninterrupted again: exiting now");
                std::process::exit(130);
            }
            eprintln!("\ninterrupt: finishing up (press Ctrl-C again to exit at once)");
        });
        if let Err(e) = r {
            eprintln!("warning: cannot install the Ctrl-C handler: {e}");
        }
    });
}

/// True once an interrupt has been requested.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst)
}
