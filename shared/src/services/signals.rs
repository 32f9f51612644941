//! SIGINT and SIGTERM, latched: once either arrives, [`termination_seen`] stays true for every
//! thread of the process; and Ctrl-Z (SIGTSTP) stops the process as it would without iceoryx2.
//!
//! iceoryx2 0.10 installs its own handler for every catchable signal (SIGINT, SIGTERM, SIGCONT,
//! SIGTSTP among them) at its first use after the first node. That handler keeps only the last
//! signal, so a SIGCONT right after a SIGTERM overwrites it. systemd sends exactly that on every
//! stop (`KillSignal`, then SIGCONT), and so does `timeout(1)`. A review stopped `corridor serve`
//! with `kill -TERM; kill -CONT`: it went on running in 1 of 3 tries, and in 5 of 6 under
//! `timeout 3`. Its SIGTSTP handler records the signal and nothing stops: Ctrl-Z did nothing.
//!
//! So, once, after the first node that handles termination requests exists
//! ([`Domain::node`](super::Domain::node) calls [`install_after_first_node`]): a handler of ours takes SIGINT and SIGTERM, records them and
//! calls the handler it replaced (iceoryx2's, whose own waits then still see them); and SIGTSTP,
//! which it passes to iceoryx2's handler and then delivers again with the default action, so the
//! kernel's rules apply (no stop for an orphaned process group, as under systemd). A SIGTSTP the
//! process was started to ignore ([`note_before_first_node`]) is ignored again. Handlers a host
//! program installs later are left alone (an earlier version re-took the signals at every poll,
//! and a host handler that chains to its predecessor then recursed: a review).

use std::sync::Once;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// Set by [`latch`] (or by a reader that saw iceoryx2 report a termination request).
static SEEN: AtomicBool = AtomicBool::new(false);

/// The handlers ours replaced, for each of [`SIGNALS`] (as `sighandler_t`).
static REPLACED: [AtomicUsize; 3] = [
    AtomicUsize::new(0),
    AtomicUsize::new(0),
    AtomicUsize::new(0),
];

/// Per signal: [`latch`] is running for it (a handler that calls back into it returns at once).
static RUNNING: [AtomicBool; 3] = [
    AtomicBool::new(false),
    AtomicBool::new(false),
    AtomicBool::new(false),
];

const SIGNALS: [libc::c_int; 3] = [libc::SIGINT, libc::SIGTERM, libc::SIGTSTP];

/// SIGTSTP was ignored before the first node (a process started so): it stays ignored.
static TSTP_IGNORED: AtomicBool = AtomicBool::new(false);

static NOTED: Once = Once::new();
static INSTALLED: Once = Once::new();

/// True once SIGINT or SIGTERM reached this process (after the latch was installed), or a
/// reader recorded iceoryx2's termination request ([`record_termination`]).
pub(crate) fn termination_seen() -> bool {
    SEEN.load(Ordering::Relaxed)
}

/// Records a termination request seen another way (iceoryx2's report).
pub(crate) fn record_termination() {
    SEEN.store(true, Ordering::Relaxed);
}

/// The current disposition of `signal`, or `None` when it cannot be read.
fn disposition(signal: libc::c_int) -> Option<libc::sigaction> {
    // SAFETY: reads the disposition into a zeroed `sigaction`.
    let mut current: libc::sigaction = unsafe { std::mem::zeroed() };
    (unsafe { libc::sigaction(signal, std::ptr::null(), &mut current) } == 0).then_some(current)
}

/// Notes, before the process's first iceoryx2 node (which installs iceoryx2's handlers over
/// every disposition), whether SIGTSTP is ignored.
pub(crate) fn note_before_first_node() {
    NOTED.call_once(|| {
        let ignored = disposition(libc::SIGTSTP).is_some_and(|d| d.sa_sigaction == libc::SIG_IGN);
        TSTP_IGNORED.store(ignored, Ordering::Relaxed);
    });
}

/// Installs [`latch`] once, over iceoryx2's handlers.
pub(crate) fn install_after_first_node() {
    INSTALLED.call_once(|| {
        // iceoryx2 creates its signal handler, and installs it, at its first use (a node's
        // first wait, a shared memory's creation), not with the node: created here, before
        // ours, or it would replace ours later. Nothing can be pending in it yet (before it,
        // SIGINT and SIGTERM had their default action), so the read loses nothing.
        if iceoryx2_bb_posix::signal::SignalHandler::termination_requested() {
            record_termination();
        }
        for (i, &signal) in SIGNALS.iter().enumerate() {
            let Some(current) = disposition(signal) else {
                continue;
            };
            if signal == libc::SIGTSTP && TSTP_IGNORED.load(Ordering::Relaxed) {
                let mut ignore = current;
                ignore.sa_sigaction = libc::SIG_IGN;
                // SAFETY: sets SIGTSTP back to ignored, as the process was started.
                unsafe { libc::sigaction(signal, &ignore, std::ptr::null_mut()) };
                continue;
            }
            if current.sa_flags & libc::SA_SIGINFO != 0 {
                // A handler of another kind than iceoryx2's: left.
                continue;
            }
            REPLACED[i].store(current.sa_sigaction, Ordering::Relaxed);
            let mut ours = current;
            ours.sa_sigaction = latch_address();
            // SAFETY: installs `latch`, a plain handler, with the mask and flags of the one it
            // replaces.
            unsafe { libc::sigaction(signal, &ours, std::ptr::null_mut()) };
        }
    });
}

fn latch_address() -> libc::sighandler_t {
    latch as extern "C" fn(libc::c_int) as libc::sighandler_t
}

/// The signal handler: records a termination request (SIGINT, SIGTERM), runs the handler it
/// replaced, and on SIGTSTP takes the default action. Only async-signal-safe work: atomics, a
/// call, `sigaction`, `sigprocmask` and `raise`.
extern "C" fn latch(signal: libc::c_int) {
    let Some(i) = SIGNALS.iter().position(|&s| s == signal) else {
        return;
    };
    if RUNNING[i].swap(true, Ordering::Relaxed) {
        return;
    }
    if signal != libc::SIGTSTP {
        SEEN.store(true, Ordering::Relaxed);
    }
    let replaced = REPLACED[i].load(Ordering::Relaxed);
    if replaced != libc::SIG_DFL && replaced != libc::SIG_IGN && replaced != latch_address() {
        // SAFETY: `replaced` was read from `sigaction` as the installed handler of this
        // signal without SA_SIGINFO, and is neither SIG_DFL nor SIG_IGN: a plain
        // `extern "C" fn(c_int)`.
        let f: extern "C" fn(libc::c_int) = unsafe { std::mem::transmute(replaced) };
        f(signal);
    }
    if signal == libc::SIGTSTP {
        stop_as_by_default();
    }
    RUNNING[i].store(false, Ordering::Relaxed);
}

/// SIGTSTP again with its default action (the process stops, unless the kernel discards it for
/// an orphaned process group), then, once continued, [`latch`] back in place.
fn stop_as_by_default() {
    // SAFETY: async-signal-safe calls on this process's own disposition and mask. SIGTSTP is
    // blocked while its handler runs: it is unblocked for the `raise`, and the kernel restores
    // the mask when the handler returns.
    unsafe {
        let mut ours: libc::sigaction = std::mem::zeroed();
        let mut default: libc::sigaction = std::mem::zeroed();
        default.sa_sigaction = libc::SIG_DFL;
        if libc::sigaction(libc::SIGTSTP, &default, &mut ours) != 0 {
            return;
        }
        let mut set: libc::sigset_t = std::mem::zeroed();
        libc::sigemptyset(&mut set);
        libc::sigaddset(&mut set, libc::SIGTSTP);
        libc::sigprocmask(libc::SIG_UNBLOCK, &set, std::ptr::null_mut());
        libc::raise(libc::SIGTSTP);
        libc::sigaction(libc::SIGTSTP, &ours, std::ptr::null_mut());
    }
}
