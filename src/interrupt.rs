//! Ctrl-C (SIGINT, SIGTERM, SIGHUP) and the process's exit paths.
//!
//! While a command runs a phase that polls between units of work (render passes: see
//! [`polling`]), the first Ctrl-C is a request: the loop stops at the next pass boundary and the
//! command writes what is complete. Anywhere else (loading a mesh, building a thread pool,
//! writing files), and on a second Ctrl-C, the process exits at once, within about a second:
//! it lets a file write in progress finish ([`critical`]: a file is then whole and renamed
//! into place, or not there), runs the registered exit hooks ([`on_exit`]: a compare run
//! records in its `run.json` that it was interrupted), removes temporary files still open
//! ([`TempRegistration`]), and exits with status 130.
//!
//! [`install`] also sets the process up so that other exits are quiet and clean: a closed
//! stdout (`dibench warp --list | head -1`) ends the process by SIGPIPE as for any Unix filter,
//! and a file-size limit (`ulimit -f`) is an I/O error like a full disk instead of a core dump.
//! (Closed standard descriptors are reopened on /dev/null by Rust's runtime before `main`.)

use std::cell::Cell;
use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering::SeqCst};
use std::sync::{Mutex, MutexGuard, Once};
use std::time::{Duration, Instant};

static REQUESTED: AtomicBool = AtomicBool::new(false);
static POLLING: AtomicUsize = AtomicUsize::new(0);
static CRITICAL: AtomicUsize = AtomicUsize::new(0);
static EXITING: AtomicBool = AtomicBool::new(false);
static NEXT_ID: AtomicU64 = AtomicU64::new(0);
type Hook = Box<dyn Fn() + Send>;
static HOOKS: Mutex<Vec<(u64, Hook)>> = Mutex::new(Vec::new());
static TEMPS: Mutex<Vec<(u64, PathBuf)>> = Mutex::new(Vec::new());
static INSTALL: Once = Once::new();

thread_local! {
    /// Critical sections this thread is inside (they nest: a store commit writes files).
    static DEPTH: Cell<usize> = const { Cell::new(0) };
    /// Set on the thread that runs the exit, which may still write (`run.json`).
    static EXIT_THREAD: Cell<bool> = const { Cell::new(false) };
}

/// How long an exit waits for file writes in progress before it removes their temporary
/// files and leaves anyway.
const WRITE_GRACE: Duration = Duration::from_secs(2);

/// Sets up the process (see the module comment) and installs the Ctrl-C handler; idempotent.
/// Failure to install the handler is not fatal: Ctrl-C then kills the process, which every
/// output survives (see `output::store`).
pub fn install() {
    INSTALL.call_once(|| {
        #[cfg(unix)]
        process_hygiene();
        #[cfg(unix)]
        let ignored = inherited_ignores();
        if let Err(e) = ctrlc::set_handler(on_signal) {
            note(&format!("warning: cannot install the Ctrl-C handler: {e}"));
        }
        #[cfg(unix)]
        for sig in ignored {
            // SAFETY: resets this process's own disposition of a signal it inherited ignored.
            unsafe {
                libc::signal(sig, libc::SIG_IGN);
            }
        }
    });
}

/// SIGHUP if this process was started with it ignored (`nohup`): it stays ignored. The handler
/// covers SIGINT, SIGTERM and SIGHUP, and would otherwise end a `nohup` run when its terminal
/// closes. (SIGINT is handled even when inherited ignored, as a shell without job control
/// starts background commands: an explicit `kill -INT` is then still a Ctrl-C.)
#[cfg(unix)]
fn inherited_ignores() -> Vec<libc::c_int> {
    [libc::SIGHUP]
        .into_iter()
        .filter(|&sig| {
            // SAFETY: queries the disposition only (a null new action).
            unsafe {
                let mut old: libc::sigaction = std::mem::zeroed();
                libc::sigaction(sig, std::ptr::null(), &mut old) == 0
                    && old.sa_sigaction == libc::SIG_IGN
            }
        })
        .collect()
}

#[cfg(unix)]
fn process_hygiene() {
    // SAFETY: plain libc calls on this process's own signal dispositions, made before any
    // other thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
    }
}

fn on_signal() {
    if POLLING.load(SeqCst) > 0 && !REQUESTED.swap(true, SeqCst) {
        note(
            "\ninterrupt: stopping after the current pass and writing what is complete \
             (Ctrl-C again to stop at once)",
        );
        return;
    }
    exit_now();
}

/// Exits with status 130 after letting writes in progress finish, running the exit hooks and
/// removing temporary files (see the module comment).
pub fn exit_now() -> ! {
    EXIT_THREAD.with(|t| t.set(true));
    EXITING.store(true, SeqCst);
    let start = Instant::now();
    while CRITICAL.load(SeqCst) > 0 && start.elapsed() < WRITE_GRACE {
        std::thread::sleep(Duration::from_millis(5));
    }
    for (_, hook) in lock(&HOOKS).iter() {
        hook();
    }
    // Held until the process ends: a write that outlived the grace cannot create a temporary
    // file after these are removed (see `create_temp`). Writers write through the file's open
    // handle, never by its name, so one still writing cannot bring a removed file back.
    let mut temps = lock(&TEMPS);
    for (_, path) in temps.drain(..) {
        let _ = std::fs::remove_file(path);
    }
    note("interrupted: exiting now");
    std::process::exit(130)
}

/// A poisoned lock still holds usable data here (lists of paths and hooks).
fn lock<T>(m: &'static Mutex<T>) -> MutexGuard<'static, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// True once an interrupt has been requested.
pub fn requested() -> bool {
    REQUESTED.load(SeqCst)
}

/// While the returned guard lives, the first Ctrl-C is a request that [`requested`] reports;
/// hold it only around loops that poll between short units of work.
#[must_use]
pub fn polling() -> Polling {
    POLLING.fetch_add(1, SeqCst);
    Polling(())
}

pub struct Polling(());

impl Drop for Polling {
    fn drop(&mut self) {
        POLLING.fetch_sub(1, SeqCst);
    }
}

/// Runs `f` (a file write and its rename, or a multi-file commit) so that an exit on Ctrl-C
/// waits for it to finish. Once an exit has begun, other threads do not start new writes.
pub fn critical<T>(f: impl FnOnce() -> T) -> T {
    let outermost = DEPTH.with(|d| d.get()) == 0;
    if outermost {
        CRITICAL.fetch_add(1, SeqCst);
        if EXITING.load(SeqCst) && !EXIT_THREAD.with(|t| t.get()) {
            CRITICAL.fetch_sub(1, SeqCst);
            // The process is about to exit; starting a write now could only leave a part.
            loop {
                std::thread::park();
            }
        }
    }
    struct Leave(bool);
    impl Drop for Leave {
        fn drop(&mut self) {
            DEPTH.with(|d| d.set(d.get() - 1));
            if self.0 {
                CRITICAL.fetch_sub(1, SeqCst);
            }
        }
    }
    DEPTH.with(|d| d.set(d.get() + 1));
    let _leave = Leave(outermost);
    f()
}

/// Runs `hook` if the process exits on Ctrl-C while the returned guard lives.
#[must_use]
pub fn on_exit(hook: impl Fn() + Send + 'static) -> ExitHook {
    let id = NEXT_ID.fetch_add(1, SeqCst);
    lock(&HOOKS).push((id, Box::new(hook)));
    ExitHook(id)
}

pub struct ExitHook(u64);

impl Drop for ExitHook {
    fn drop(&mut self) {
        lock(&HOOKS).retain(|(id, _)| *id != self.0);
    }
}

/// Creates a temporary file with `create` and registers it, so that an exit on Ctrl-C that
/// cannot wait for its write removes it. Creation and registration are one step under the
/// registry's lock, which the exit holds from removing the registered files to its end: every
/// temporary file is either registered before they are removed, or never created.
pub fn create_temp<E>(
    create: impl FnOnce() -> Result<tempfile::NamedTempFile, E>,
) -> Result<(tempfile::NamedTempFile, TempRegistration), E> {
    let mut temps = lock(&TEMPS);
    if EXITING.load(SeqCst) && !EXIT_THREAD.with(|t| t.get()) {
        drop(temps);
        // The process is about to exit; the file could only be left behind.
        loop {
            std::thread::park();
        }
    }
    let file = create()?;
    let id = NEXT_ID.fetch_add(1, SeqCst);
    temps.push((id, file.path().to_path_buf()));
    Ok((file, TempRegistration(id)))
}

pub struct TempRegistration(u64);

impl Drop for TempRegistration {
    fn drop(&mut self) {
        lock(&TEMPS).retain(|(id, _)| *id != self.0);
    }
}

/// A line on stderr that cannot fail the program (stderr may be closed or a broken pipe).
pub fn note(line: &str) {
    let _ = writeln!(std::io::stderr(), "{line}");
}
