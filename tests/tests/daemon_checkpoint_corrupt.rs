//! A damaged checkpoint becomes a warning, is renamed `<file>.corrupt-1`, and the daemon starts
//! from the configured prior (in-process; its own binary, one daemon a process).

mod daemon_common;

use corridor_client::Domain;
use corridor_service::checkpoint;
use daemon_common::*;

#[test]
fn corrupt_checkpoint_is_moved_aside_and_the_daemon_cold_starts() {
    let _one = one_daemon_at_a_time();
    let name = "test_daemon_corrupt";
    cleanup_domain(name);
    let dir = temp_dir("test-daemon-corrupt");
    let ckpt = dir.join("checkpoint.bin");
    let mut garbage = checkpoint::MAGIC.to_vec();
    garbage.extend_from_slice(&checkpoint::FORMAT_VERSION.to_le_bytes());
    garbage.extend_from_slice(b" this is not bincode");
    std::fs::write(&ckpt, &garbage).unwrap();
    let domain = Domain::new(name).unwrap();
    let (offline, first_aligned) = offline_exp36();

    let (first, report) = first_aligned_bias(&domain, &ckpt, first_aligned + 50);
    assert!(report.warm_started_from.is_none());
    assert_eq!(report.warnings.len(), 1, "{:?}", report.warnings);
    let w = &report.warnings[0];
    assert!(
        w.contains("corrupt checkpoint") && w.contains("cold start"),
        "{w}"
    );
    let aside = dir.join("checkpoint.bin.corrupt-1");
    assert!(w.contains(&aside.display().to_string()), "{w}");
    assert_eq!(std::fs::read(&aside).unwrap(), garbage, "kept aside as is");

    // Cold start: exactly the offline run's bias at alignment (configured rest-mean prior).
    let cold = offline[first_aligned];
    assert_eq!(first.imu_seq, first_aligned as u64);
    assert_eq!(first.gyro_bias_rad_s, cold.gyro_bias_rad_s);
    assert_eq!(first.gyro_bias_sd_rad_s, cold.gyro_bias_sd_rad_s);
    // And a valid checkpoint replaced the corrupt one.
    let cp = checkpoint::load(&ckpt).expect("new checkpoint");
    assert_eq!(cp.t_s, offline[first_aligned + 49].t_s);

    cleanup_domain(name);
}
