//! SIGTERM followed by SIGCONT (systemd's stop, `timeout(1)`) is still a termination request
//! (`services::termination_requested`): iceoryx2 keeps only the last signal, and lost it. Its
//! own test binary: the request, once seen, holds for the whole process.

use corridor_shared::services::{Domain, node_sleep, termination_requested};
use iceoryx2::prelude::SignalHandlingMode;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

/// The SIGTERM handler a host program had installed before its first node.
static EARLY_CALLS: AtomicUsize = AtomicUsize::new(0);

extern "C" fn early_handler(_signal: libc::c_int) {
    EARLY_CALLS.fetch_add(1, Ordering::Relaxed);
}

/// Sets `signal`'s handler (a plain one, or SIG_IGN).
fn set_handler(signal: libc::c_int, handler: libc::sighandler_t) {
    // SAFETY: installs a plain handler (or SIG_IGN) for this process.
    unsafe {
        let mut action: libc::sigaction = std::mem::zeroed();
        action.sa_sigaction = handler;
        assert_eq!(libc::sigaction(signal, &action, std::ptr::null_mut()), 0);
    }
}

/// The handler a host program installed after corridor's, and the one it replaced.
static HOST_CALLS: AtomicUsize = AtomicUsize::new(0);
static HOST_PREVIOUS: AtomicUsize = AtomicUsize::new(0);

extern "C" fn host_handler(signal: libc::c_int) {
    HOST_CALLS.fetch_add(1, Ordering::Relaxed);
    let previous = HOST_PREVIOUS.load(Ordering::Relaxed);
    if previous != libc::SIG_DFL && previous != libc::SIG_IGN {
        // SAFETY: the plain handler that was installed before this one.
        let f: extern "C" fn(libc::c_int) = unsafe { std::mem::transmute(previous) };
        f(signal);
    }
}

fn handler_of(signal: libc::c_int) -> libc::sighandler_t {
    // SAFETY: reads the disposition into a zeroed `sigaction`.
    let mut current: libc::sigaction = unsafe { std::mem::zeroed() };
    assert_eq!(
        unsafe { libc::sigaction(signal, std::ptr::null(), &mut current) },
        0
    );
    current.sa_sigaction
}

#[test]
fn sigterm_then_sigcont_is_still_a_termination_request() {
    // Before the first node, the host program has a SIGTERM handler of its own, and SIGINT
    // ignored, as a script's `&` job has it.
    set_handler(
        libc::SIGTERM,
        early_handler as extern "C" fn(libc::c_int) as libc::sighandler_t,
    );
    set_handler(libc::SIGINT, libc::SIG_IGN);
    let domain = Domain::new("test_termination_latch").unwrap();
    let node = domain
        .node("latch", SignalHandlingMode::HandleTerminationRequests)
        .unwrap();
    // SIGINT stays ignored (iceoryx2 put its handler over it: a Ctrl-C meant for the script
    // stopped the job).
    assert_eq!(handler_of(libc::SIGINT), libc::SIG_IGN);
    // A sleep that nothing interrupts goes on; nothing was requested.
    assert!(node_sleep(&node, Duration::from_millis(10)));
    assert!(!termination_requested(&node));
    // SAFETY: raise(3) on this process. SIGTERM reaches the handlers installed above (the
    // latch, then iceoryx2's); SIGCONT iceoryx2's, which overwrites the signal it keeps.
    unsafe {
        libc::raise(libc::SIGTERM);
        libc::raise(libc::SIGCONT);
    }
    assert!(termination_requested(&node));
    assert!(!node_sleep(&node, Duration::from_millis(10)));
    // The host's own SIGTERM handler still runs (after iceoryx2's).
    assert_eq!(EARLY_CALLS.load(Ordering::Relaxed), 1);

    // A host program that installs its own SIGTERM handler afterwards, chaining to the one it
    // replaced (corridor's): left in place by later nodes and polls (an earlier latch took the
    // signal back at every poll, and the two handlers then called each other without end).
    let host = host_handler as extern "C" fn(libc::c_int) as libc::sighandler_t;
    // SAFETY: installs a plain handler, keeping the previous one to chain to.
    unsafe {
        let mut ours: libc::sigaction = std::mem::zeroed();
        ours.sa_sigaction = host;
        let mut previous: libc::sigaction = std::mem::zeroed();
        assert_eq!(libc::sigaction(libc::SIGTERM, &ours, &mut previous), 0);
        HOST_PREVIOUS.store(previous.sa_sigaction, Ordering::Relaxed);
    }
    let second = domain
        .node("latch-2", SignalHandlingMode::HandleTerminationRequests)
        .unwrap();
    assert!(!node_sleep(&second, Duration::from_millis(10)));
    assert!(termination_requested(&second));
    assert_eq!(handler_of(libc::SIGTERM), host);
    // SAFETY: raise(3) on this process: the host's handler, then corridor's (iceoryx2's and
    // the early one), once each.
    unsafe { libc::raise(libc::SIGTERM) };
    assert_eq!(HOST_CALLS.load(Ordering::Relaxed), 1);
    assert_eq!(EARLY_CALLS.load(Ordering::Relaxed), 2);
}
