//! Temporary output files removed when the process is interrupted.
//!
//! [`super::write_atomic_with`] writes into a temp file beside its target
//! and renames it into place. A panic or an error drops the temp file, but a
//! signal ends the process without running destructors, so Ctrl-C in the
//! middle of a write would leave `.NAME.XXXXXX.tmp` behind. The rule here:
//! every temp file is listed in a process-wide registry from right after
//! its creation until it is renamed or removed; a process that called
//! [`remove_temp_files_on_signal`] answers SIGINT, SIGTERM and SIGHUP by
//! removing every listed file and then dying of that signal as it would
//! have without a handler (the shell sees 130 for Ctrl-C, 143 for SIGTERM).
//!
//! Opt-in, because a handler changes what a signal does for the whole
//! process: the CLI opts in; a library user (a Python host with its own
//! `KeyboardInterrupt`) keeps its own handling. The handler is installed
//! lazily, at the first write after opting in, so a process that never
//! writes (a server with its own graceful Ctrl-C) is untouched. On
//! non-Unix targets the registry is kept but no handler is installed; on
//! wasm32, where nothing writes files, there is no registry.
//!
//! A caller that stages a whole folder (the CLI's `build`) lists it with
//! [`TempGuard::new`]; the handler removes a listed folder with everything
//! in it.
//!
//! Left open: a signal in the instant between the temp file's creation
//! and its registration (a few instructions) leaves it behind; SIGKILL
//! cannot be caught.

#[cfg(not(target_arch = "wasm32"))]
use std::path::{Path, PathBuf};
#[cfg(not(target_arch = "wasm32"))]
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};

#[cfg(not(target_arch = "wasm32"))]
/// Temp files that exist now, in creation order (a write may be running in
/// several threads at once).
static PENDING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
static ENABLED: AtomicBool = AtomicBool::new(false);
#[cfg(unix)]
static INSTALL: std::sync::Once = std::sync::Once::new();

/// From now on, SIGINT, SIGTERM and SIGHUP remove every temp file a
/// running [`super::write_atomic`] holds before the process dies of the
/// signal (see the module docs). Idempotent; cheap (the handler thread
/// starts at the next write).
pub fn remove_temp_files_on_signal() {
    ENABLED.store(true, Ordering::SeqCst);
}

#[cfg(not(target_arch = "wasm32"))]
/// A temp file listed in the registry while this lives.
pub(crate) struct Pending {
    path: PathBuf,
}

#[cfg(not(target_arch = "wasm32"))]
impl Pending {
    /// Lists `path` (installing the handler first if the process opted in).
    pub(crate) fn new(path: &Path) -> Pending {
        #[cfg(unix)]
        if ENABLED.load(Ordering::SeqCst) {
            INSTALL.call_once(install);
        }
        lock().push(path.to_path_buf());
        Pending {
            path: path.to_path_buf(),
        }
    }
}

#[cfg(not(target_arch = "wasm32"))]
impl Drop for Pending {
    fn drop(&mut self) {
        let mut list = lock();
        if let Some(i) = list.iter().rposition(|p| *p == self.path) {
            list.remove(i);
        }
    }
}

#[cfg(not(target_arch = "wasm32"))]
/// A temporary file or folder of the caller's, removed (a folder with
/// everything in it) if the process dies of SIGINT, SIGTERM or SIGHUP
/// while this guard lives and the process opted in with
/// [`remove_temp_files_on_signal`]. Dropping the guard only unlists the
/// path: removing or renaming it on the normal path is the caller's job.
pub struct TempGuard {
    _pending: Pending,
}

#[cfg(not(target_arch = "wasm32"))]
impl TempGuard {
    /// Lists `path` until the guard is dropped. Cost: one lock and a push.
    pub fn new(path: &Path) -> TempGuard {
        TempGuard {
            _pending: Pending::new(path),
        }
    }
}

#[cfg(not(target_arch = "wasm32"))]
/// The registry, even if a thread panicked while holding it (the list
/// itself is always valid).
fn lock() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    PENDING.lock().unwrap_or_else(|e| e.into_inner())
}

/// Starts the thread that waits for the signals. If the handler cannot be
/// registered, signals keep their default action (no cleanup, no harm).
#[cfg(unix)]
fn install() {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
        return;
    };
    let spawned = std::thread::Builder::new()
        .name("lodkit-signals".into())
        .spawn(move || {
            if let Some(sig) = signals.forever().next() {
                // Held until the process is gone: no write registers or
                // renames a file past this point.
                let list = lock();
                for p in list.iter() {
                    // A listed folder is a staged output (`TempGuard`).
                    if std::fs::symlink_metadata(p).is_ok_and(|m| m.is_dir()) {
                        // The command's other threads may still be adding
                        // files to it (a removal then fails on a folder no
                        // longer empty, or the folder comes back with a
                        // subfolder): try until it is gone, a bounded while.
                        for _ in 0..200 {
                            let _ = std::fs::remove_dir_all(p);
                            if std::fs::symlink_metadata(p).is_err() {
                                break;
                            }
                            std::thread::sleep(std::time::Duration::from_millis(2));
                        }
                    } else {
                        let _ = std::fs::remove_file(p);
                    }
                }
                let _ = signal_hook::low_level::emulate_default_handler(sig);
                std::process::exit(128 + sig);
            }
        });
    drop(spawned);
}
