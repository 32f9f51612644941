//! SIGINT and SIGTERM, latched: once either arrives, [`termination_seen`] stays true for every
//! thread of the process.
//!
//! iceoryx2 0.10 installs its own handler for SIGINT, SIGTERM and SIGCONT (among others) the
//! first time it creates shared memory or a node waits. That handler keeps only the last
//! signal, so a SIGCONT right after a SIGTERM overwrites it. systemd sends exactly that on
//! every stop (`KillSignal`, then SIGCONT), and so does `timeout(1)`. A review stopped
//! `corridor serve` with `kill -TERM; kill -CONT`: it went on running in 1 of 3 tries, and in 5 of
//! 6 under `timeout 3`. Here a handler of ours takes SIGINT and SIGTERM, records them, and then
//! calls the handler it replaced (iceoryx2's), so iceoryx2's own waits still see them.
//!
//! iceoryx2 may install its handler after ours (its handler is created lazily), so
//! [`ensure_latched`] checks and re-installs at every poll (one `sigaction` call per signal).

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// Set by [`latch`] (or by a reader that saw iceoryx2 report a termination request).
static SEEN: AtomicBool = AtomicBool::new(false);

/// The handlers ours replaced, for each of [`SIGNALS`] (as `sighandler_t`).
static REPLACED: [AtomicUsize; 3] = [
    AtomicUsize::new(0),
    AtomicUsize::new(0),
    AtomicUsize::new(0),
];

/// The signals [`latch`] takes. SIGTSTP (Ctrl-Z) too: iceoryx2's handler records it and
/// nothing stops, so Ctrl-Z did nothing to the daemon or a client tool; ours runs that handler
/// and then stops the process as the default action would.
const SIGNALS: [libc::c_int; 3] = [libc::SIGINT, libc::SIGTERM, libc::SIGTSTP];

/// True once SIGINT or SIGTERM reached this process (after [`ensure_latched`] first ran), or a
/// reader recorded iceoryx2's termination request ([`record_termination`]).
pub(crate) fn termination_seen() -> bool {
    SEEN.load(Ordering::Relaxed)
}

/// Records a termination request seen another way (iceoryx2's report).
pub(crate) fn record_termination() {
    SEEN.store(true, Ordering::Relaxed);
}

/// The signal handler: records a termination request (SIGINT, SIGTERM), runs the handler it
/// replaced, and stops the process on SIGTSTP. Only async-signal-safe work: atomics, a call
/// and `raise`.
extern "C" fn latch(signal: libc::c_int) {
    let Some(i) = SIGNALS.iter().position(|&s| s == signal) else {
        return;
    };
    if signal != libc::SIGTSTP {
        SEEN.store(true, Ordering::Relaxed);
    }
    let replaced = REPLACED[i].load(Ordering::Relaxed);
    if replaced != libc::SIG_DFL && replaced != libc::SIG_IGN && replaced != latch_address() {
        // SAFETY: `replaced` was read from `sigaction` as the installed handler of this
        // signal, and it is neither SIG_DFL nor SIG_IGN: a plain `extern "C" fn(c_int)` (ours
        // is installed without SA_SIGINFO, as iceoryx2's is).
        let f: extern "C" fn(libc::c_int) = unsafe { std::mem::transmute(replaced) };
        f(signal);
    }
    if signal == libc::SIGTSTP {
        // SAFETY: raise(3) is async-signal-safe; SIGSTOP stops the process until SIGCONT.
        unsafe { libc::raise(libc::SIGSTOP) };
    }
}

fn latch_address() -> libc::sighandler_t {
    latch as extern "C" fn(libc::c_int) as libc::sighandler_t
}

/// Installs [`latch`] for [`SIGNALS`] where another handler is installed now (iceoryx2's, or
/// the default; SIGTSTP set to be ignored is left). Cheap enough for every poll.
pub(crate) fn ensure_latched() {
    for (i, &signal) in SIGNALS.iter().enumerate() {
        // SAFETY: reading the current disposition into a zeroed `sigaction`.
        let mut current: libc::sigaction = unsafe { std::mem::zeroed() };
        if unsafe { libc::sigaction(signal, std::ptr::null(), &mut current) } != 0 {
            continue;
        }
        if current.sa_sigaction == latch_address()
            || current.sa_flags & libc::SA_SIGINFO != 0
            || (signal == libc::SIGTSTP && current.sa_sigaction == libc::SIG_IGN)
        {
            // Ours already, a handler of another kind this latch cannot chain to, or a Ctrl-Z
            // the process was started to ignore: left.
            continue;
        }
        REPLACED[i].store(current.sa_sigaction, Ordering::Relaxed);
        let mut ours = current;
        ours.sa_sigaction = latch_address();
        // SAFETY: installs `latch`, a plain handler, with the mask and flags of the one it
        // replaces.
        unsafe { libc::sigaction(signal, &ours, std::ptr::null_mut()) };
    }
}
