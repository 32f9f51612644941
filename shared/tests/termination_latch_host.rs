//! A host program's own SIGINT handler, installed before corridor's first node and again after
//! iceoryx2 set its handlers up, is called once per signal (the latch called it twice: as the
//! handler it replaced, and as the one noted before the first node). Its own test binary: the
//! latch is installed once per process.

use corridor_shared::services::{Domain, termination_requested};
use iceoryx2::prelude::SignalHandlingMode;
use std::sync::atomic::{AtomicUsize, Ordering};

static CALLS: AtomicUsize = AtomicUsize::new(0);

extern "C" fn host_handler(_signal: libc::c_int) {
    CALLS.fetch_add(1, Ordering::Relaxed);
}

fn set_host_handler() {
    // SAFETY: installs a plain handler for this process.
    unsafe {
        let mut action: libc::sigaction = std::mem::zeroed();
        action.sa_sigaction = host_handler as extern "C" fn(libc::c_int) as libc::sighandler_t;
        assert_eq!(
            libc::sigaction(libc::SIGINT, &action, std::ptr::null_mut()),
            0
        );
    }
}

#[test]
fn a_host_handler_installed_twice_is_called_once() {
    set_host_handler();
    let domain = Domain::new("test_termination_latch_host").unwrap();
    // A node that does not handle termination requests: noted, nothing installed.
    let _quiet = domain.node("quiet", SignalHandlingMode::Disabled).unwrap();
    // iceoryx2's handlers set up by the host's own use of iceoryx2, and its handler again.
    let _ = iceoryx2_bb_posix::signal::SignalHandler::last_signal();
    set_host_handler();
    let node = domain
        .node("handling", SignalHandlingMode::HandleTerminationRequests)
        .unwrap();
    // SAFETY: raise(3) on this process: the latch, then the host's handler it replaced.
    unsafe { libc::raise(libc::SIGINT) };
    assert_eq!(CALLS.load(Ordering::Relaxed), 1);
    assert!(termination_requested(&node));
}
