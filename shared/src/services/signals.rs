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
//! kernel's rules apply (no stop for an orphaned process group, as under systemd). A signal the
//! process was started to ignore ([`note_before_first_node`]: SIGINT for a script's `&` job) is
//! ignored again, and a plain handler the host program had installed before is called after
//! iceoryx2's. Handlers a host program installs later are left alone (an earlier version re-took
//! the signals at every poll, and a host handler that chains to its predecessor then recursed:
//! a review). Left: iceoryx2 installs SIGCONT's handler before SIGTERM's and ours follows a few
//! system calls later; a SIGTERM and a SIGCONT both within those microseconds of the first node
//! lose the stop as before (not seen in 162 tries of `timeout` at 10–90 ms). iceoryx2's handler
//! also takes SIGQUIT and SIGUSR1 (they do nothing), and a termination request, once seen, holds
//! for the process's life.

use std::sync::Once;
use std::sync::atomic::{AtomicBool, AtomicI32, AtomicUsize, Ordering};

/// Set by [`latch`] (or by a reader that saw iceoryx2 report a termination request).
static SEEN: AtomicBool = AtomicBool::new(false);

/// The first SIGINT or SIGTERM [`latch`] took (0 before one, or when only iceoryx2 reported
/// the request).
static FIRST_SIGNAL: AtomicI32 = AtomicI32::new(0);

const SIGNALS: [libc::c_int; 3] = [libc::SIGINT, libc::SIGTERM, libc::SIGTSTP];

/// What the latch keeps for one of [`SIGNALS`].
struct Slot {
    /// The handler ours replaced (iceoryx2's), as `sighandler_t`.
    replaced: AtomicUsize,
    /// What the process had before iceoryx2's handler, as noted by [`note_before_first_node`]:
    /// `SIG_IGN` (a job a script started with `&` ignores SIGINT), a plain handler of the host
    /// program's own (called after iceoryx2's), or `SIG_DFL`.
    before: AtomicUsize,
    /// The host program has a handler of its own for it (then it, not the latch, decides what
    /// SIGTSTP does).
    host_handles: AtomicBool,
    /// [`latch`] is running for it (a handler that calls back into it returns at once).
    running: AtomicBool,
}

/// One [`Slot`] per signal of [`SIGNALS`], in its order.
static SLOTS: [Slot; 3] = [const {
    Slot {
        replaced: AtomicUsize::new(0),
        before: AtomicUsize::new(libc::SIG_DFL),
        host_handles: AtomicBool::new(false),
        running: AtomicBool::new(false),
    }
}; 3];

static NOTED: Once = Once::new();
static INSTALLED: Once = Once::new();

/// True once SIGINT or SIGTERM reached this process (after the latch was installed), or a
/// reader recorded iceoryx2's termination request ([`record_termination`]).
pub(crate) fn termination_seen() -> bool {
    // Acquire: a reader that sees the request sees the signal recorded before it.
    SEEN.load(Ordering::Acquire)
}

/// Records a termination request seen another way (iceoryx2's report).
pub(crate) fn record_termination() {
    SEEN.store(true, Ordering::Release);
}

/// The signal that asked this process to end: the first SIGINT or SIGTERM, SIGINT when only
/// iceoryx2 reported the request (it does not say which); `None` without a request.
pub(crate) fn termination_signal() -> Option<libc::c_int> {
    termination_seen().then(|| match FIRST_SIGNAL.load(Ordering::Relaxed) {
        0 => libc::SIGINT,
        signal => signal,
    })
}

/// Ends the process as `signal` would have without a handler (its default action: the process
/// terminates by that signal, a shell's `$?` is 128 + its number, 130 for Ctrl-C, and systemd
/// takes a SIGTERM so as a clean stop), once the work it interrupted has been wound up; exit
/// code 128 + `signal` if it survives that.
pub(crate) fn end_as_terminated_by(signal: libc::c_int) -> ! {
    use std::io::Write as _;
    let _ = std::io::stdout().flush();
    let _ = std::io::stderr().flush();
    // SAFETY: the signal's default disposition, unblocked, and raised on this thread.
    unsafe {
        libc::signal(signal, libc::SIG_DFL);
        let mut set: libc::sigset_t = std::mem::zeroed();
        libc::sigemptyset(&mut set);
        libc::sigaddset(&mut set, signal);
        libc::pthread_sigmask(libc::SIG_UNBLOCK, &set, std::ptr::null_mut());
        libc::raise(signal);
    }
    std::process::exit(128 + signal)
}

/// The current disposition of `signal`, or `None` when it cannot be read.
fn disposition(signal: libc::c_int) -> Option<libc::sigaction> {
    // SAFETY: reads the disposition into a zeroed `sigaction`.
    let mut current: libc::sigaction = unsafe { std::mem::zeroed() };
    (unsafe { libc::sigaction(signal, std::ptr::null(), &mut current) } == 0).then_some(current)
}

/// Notes, before the process's first iceoryx2 node (iceoryx2 installs its handlers over every
/// disposition without looking at it), what each of [`SIGNALS`] had: ignored, or a plain
/// handler of the host program's. (A handler with `SA_SIGINFO` cannot be called from a plain
/// one: it is noted as the default, and replaced as iceoryx2 always replaced it.)
pub(crate) fn note_before_first_node() {
    NOTED.call_once(|| {
        for (i, &signal) in SIGNALS.iter().enumerate() {
            if let Some(d) = disposition(signal)
                && d.sa_flags & libc::SA_SIGINFO == 0
            {
                SLOTS[i].before.store(d.sa_sigaction, Ordering::Relaxed);
            }
        }
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
        // iceoryx2's handler, as it stands on SIGCONT (which no one else here takes).
        let iceoryx2_handler = disposition(libc::SIGCONT).map(|d| d.sa_sigaction);
        for (i, &signal) in SIGNALS.iter().enumerate() {
            let Some(current) = disposition(signal) else {
                continue;
            };
            // What was noted before the first node is the host program's own handler only if
            // it is not iceoryx2's (iceoryx2 used before corridor's first node: Ctrl-Z then did
            // nothing) and not the one replaced now, which the latch calls already (it was
            // called twice: a review).
            let before = SLOTS[i].before.load(Ordering::Relaxed);
            let a_handler = before != libc::SIG_DFL && before != libc::SIG_IGN;
            let iceoryx2s = Some(before) == iceoryx2_handler;
            SLOTS[i]
                .host_handles
                .store(a_handler && !iceoryx2s, Ordering::Relaxed);
            if iceoryx2s || (a_handler && before == current.sa_sigaction) {
                SLOTS[i].before.store(libc::SIG_DFL, Ordering::Relaxed);
            }
            if SLOTS[i].before.load(Ordering::Relaxed) == libc::SIG_IGN {
                let mut ignore = current;
                ignore.sa_sigaction = libc::SIG_IGN;
                // SAFETY: sets the signal back to ignored, as the process was started (a
                // review: a daemon started by a script with `&` took a Ctrl-C meant for the
                // script as a stop request).
                unsafe { libc::sigaction(signal, &ignore, std::ptr::null_mut()) };
                continue;
            }
            if current.sa_flags & libc::SA_SIGINFO != 0 {
                // A handler of another kind than iceoryx2's: left.
                continue;
            }
            SLOTS[i]
                .replaced
                .store(current.sa_sigaction, Ordering::Relaxed);
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
    if SLOTS[i].running.swap(true, Ordering::Relaxed) {
        return;
    }
    if signal != libc::SIGTSTP {
        let _ = FIRST_SIGNAL.compare_exchange(0, signal, Ordering::Relaxed, Ordering::Relaxed);
        // Release: the signal is recorded before the request is seen (a review: a reader on a
        // weakly ordered CPU could otherwise take a SIGTERM for a SIGINT).
        SEEN.store(true, Ordering::Release);
    }
    // iceoryx2's handler, then the host program's from before the first node, if any.
    for handler in [
        SLOTS[i].replaced.load(Ordering::Relaxed),
        SLOTS[i].before.load(Ordering::Relaxed),
    ] {
        if handler != libc::SIG_DFL && handler != libc::SIG_IGN && handler != latch_address() {
            // SAFETY: `handler` was read from `sigaction` as an installed handler of this
            // signal without SA_SIGINFO, and is neither SIG_DFL nor SIG_IGN: a plain
            // `extern "C" fn(c_int)`.
            let f: extern "C" fn(libc::c_int) = unsafe { std::mem::transmute(handler) };
            f(signal);
        }
    }
    // A host program's own SIGTSTP handler decides what Ctrl-Z does; otherwise the default.
    if signal == libc::SIGTSTP && !SLOTS[i].host_handles.load(Ordering::Relaxed) {
        stop_as_by_default();
    }
    SLOTS[i].running.store(false, Ordering::Relaxed);
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
        // Blocked again before ours is back (a second Ctrl-Z in between would find the latch
        // running and be lost): one pending now comes when the handler returns.
        libc::sigprocmask(libc::SIG_BLOCK, &set, std::ptr::null_mut());
        libc::sigaction(libc::SIGTSTP, &ours, std::ptr::null_mut());
    }
}
