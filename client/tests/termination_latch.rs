//! A Ctrl-C read by one thread's node is seen by every other (iceoryx2 clears a signal when it
//! is read, so the replay's watch thread took it from the replay loop, which then never
//! stopped). Its own test binary: the signal and the latch belong to the process. SIGTERM
//! stands in for the Ctrl-C: a test run started in the background (`cmd &` in a script) has
//! SIGINT ignored, and an ignored SIGINT now stays ignored.

use corridor_client::Domain;
use corridor_shared::services::node_sleep;
use iceoryx2::prelude::SignalHandlingMode;
use std::time::{Duration, Instant};

#[test]
fn a_termination_request_read_through_one_node_is_seen_through_the_others() {
    let d = Domain::new("corridor-latch-test").unwrap();
    let a = d
        .node("latch-a", SignalHandlingMode::HandleTerminationRequests)
        .unwrap();
    let b = d
        .node("latch-b", SignalHandlingMode::HandleTerminationRequests)
        .unwrap();
    assert!(!corridor_client::termination_requested(&a));
    let pid = std::process::id().to_string();
    let sent = std::process::Command::new("kill")
        .args(["-TERM", &pid])
        .status()
        .unwrap();
    assert!(sent.success());
    // Delivered asynchronously: read first by a sleep on one node, as a subscriber that is
    // opening reads it (its reader once kept it from everyone else, a review).
    let deadline = Instant::now() + Duration::from_secs(10);
    while node_sleep(&a, Duration::from_millis(5)) {
        assert!(Instant::now() < deadline, "SIGTERM never seen");
    }
    // The other node's reader sees it as well, from another thread, and again later.
    let seen_by_b = std::thread::scope(|s| {
        s.spawn(|| corridor_client::termination_requested(&b))
            .join()
            .unwrap()
    });
    assert!(seen_by_b, "the request read through `a` was lost to `b`");
    assert!(corridor_client::termination_requested(&a));
    assert!(
        !node_sleep(&b, Duration::from_millis(1)),
        "a sleep after it ends at once"
    );
}
