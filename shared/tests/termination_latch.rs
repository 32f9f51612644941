//! SIGTERM followed by SIGCONT (systemd's stop, `timeout(1)`) is still a termination request
//! (`services::termination_requested`): iceoryx2 keeps only the last signal, and lost it. Its
//! own test binary: the request, once seen, holds for the whole process.

use corridor_shared::services::{Domain, node_sleep, termination_requested};
use iceoryx2::prelude::SignalHandlingMode;
use std::time::Duration;

#[test]
fn sigterm_then_sigcont_is_still_a_termination_request() {
    let domain = Domain::new("test_termination_latch").unwrap();
    let node = domain
        .node("latch", SignalHandlingMode::HandleTerminationRequests)
        .unwrap();
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
}
