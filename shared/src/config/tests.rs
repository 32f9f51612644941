//! The configuration's validation: keys, values, rules between keys and the `[daemon]` section.

use super::*;

#[test]
fn defaults_are_valid() {
    let c = Config::default();
    assert_eq!(c.mode, Mode::Eskf);
    assert_eq!(c.detector.window, 5);
    assert!((c.heading.grid_step_rad.get() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
}

#[test]
fn the_checked_numbers_refuse_what_their_type_says_they_cannot_hold() {
    for v in [0.0, 0.5, 1e3] {
        assert_eq!(NonNegative::new("k", v).unwrap().get(), v);
        assert_eq!(Finite::new("k", -v).unwrap().get(), -v);
    }
    for v in [-1e-12, -1.0, f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let err = NonNegative::new("a.key", v).unwrap_err().to_string();
        assert!(err.contains("a.key") && err.contains(">= 0"), "{v}: {err}");
    }
    for v in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let err = Finite::new("a.key", v).unwrap_err().to_string();
        assert!(
            err.contains("a.key") && err.contains("finite"),
            "{v}: {err}"
        );
    }
    // Degrees checked as written, kept in radians.
    let a = Finite::from_degrees_in_range("h.deg", -90.0, -360.0, 360.0, "in range").unwrap();
    assert_eq!(a.get(), (-90f64).to_radians());
    assert!(Finite::from_degrees_in_range("h.deg", 400.0, -360.0, 360.0, "r").is_err());
    // A NaN passes no range: every key that may be 0 refuses it in the file.
    for key in [
        "[estimator]\nmax_bridge_s = nan\n",
        "[alignment]\nrest_tail_s = nan\n",
        "[eskf]\nzupt_rolling_height_m = nan\n",
        "[heading]\ngrid_deg = nan\n",
        "[model]\naccel_scale_factor = nan\n",
    ] {
        let f = ConfigFile::parse(key, Path::new("a.toml")).unwrap();
        let err = f.validate().unwrap_err().to_string();
        assert!(err.contains("NaN"), "{key}: {err}");
    }
}

#[test]
fn unknown_key_is_named() {
    let err = ConfigFile::parse("[detector]\nthreshhold = 3.0\n", Path::new("x.toml"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("threshhold"), "{err}");
    assert!(err.contains("x.toml"), "{err}");
}

#[test]
fn a_value_of_the_wrong_type_is_named_by_its_dotted_key() {
    // It gave the line, the column and the quoted line, but not the key (a review).
    let text = "[estimator]\nmode = \"eskf\"\n\n[eskf]\ngyro_noise_rad_s = \"abc\"\n";
    let err = ConfigFile::parse(text, Path::new("x.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with("x.toml: TOML parse error at line 5, column 20\n"),
        "{err}"
    );
    assert!(err.contains("5 | gyro_noise_rad_s = \"abc\"\n"), "{err}");
    assert!(
        err.ends_with("\nkey `eskf.gyro_noise_rad_s`: invalid type: string \"abc\", expected f64"),
        "{err}"
    );
    // An unknown key: its table.
    let err = ConfigFile::parse("[eskf]\ngyro_nosie_rad_s = 0.01\n", Path::new("x.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("\nin [eskf]: unknown field `gyro_nosie_rad_s`, expected one of"),
        "{err}"
    );
    // A syntax error has no key: the crate's message as it was.
    let err = ConfigFile::parse("[eskf]\ngyro_noise_rad_s = \n", Path::new("x.toml"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("line 2") && !err.contains("key `"), "{err}");
}

#[test]
fn the_removed_convergence_key_names_its_replacement() {
    let f = ConfigFile::parse(
        "[estimator]\nconverged_sd_rad_s = 5e-4\n",
        Path::new("a.toml"),
    )
    .unwrap();
    let err = f.validate().unwrap_err().to_string();
    assert!(err.contains("estimator.converged_sd_rad_s"), "{err}");
    assert!(err.contains("estimator.converged_unabsorbed"), "{err}");
    let f = ConfigFile::parse(
        "[estimator]\nconverged_unabsorbed = 1.5\n",
        Path::new("a.toml"),
    )
    .unwrap();
    let err = f.validate().unwrap_err().to_string();
    assert!(
        err.contains("estimator.converged_unabsorbed") && err.contains("1.5"),
        "{err}"
    );
}

#[test]
fn a_rule_between_two_keys_names_both_values() {
    // A plausible magnitude below its range: the error is the maximum's rule, and it shows
    // the range too.
    for (text, key, other) in [
        (
            "[sensor]\ngyro_range_rad_s = 50\nmax_gyro_rad_s = 40\n",
            "sensor.max_gyro_rad_s",
            "sensor.gyro_range_rad_s = 50",
        ),
        (
            "[sensor]\nmax_dt_s = 1e-9\n",
            "sensor.min_dt_s",
            "sensor.max_dt_s = 1e-9",
        ),
        (
            "[detector]\nmin_stance_s = 0.0\nlate_stance_min_s = 0.02\n",
            "detector.late_stance_min_s",
            "detector.min_stance_s = 0",
        ),
    ] {
        let f = ConfigFile::parse(text, Path::new("a.toml")).unwrap();
        let err = f.validate().unwrap_err().to_string();
        assert!(err.contains(key) && err.contains(other), "{err}");
    }
}

#[test]
fn a_covariance_step_outside_0_to_0_1_s_is_refused() {
    for (text, shown) in [
        ("[eskf]\ncovariance_step_s = -0.01\n", "-0.01"),
        ("[eskf]\ncovariance_step_s = 0.2\n", "0.2"),
        ("[eskf]\ncovariance_step_s = nan\n", "NaN"),
    ] {
        let f = ConfigFile::parse(text, Path::new("a.toml")).unwrap();
        let err = f.validate().unwrap_err().to_string();
        assert!(
            err.contains("eskf.covariance_step_s") && err.contains(shown),
            "{text}: {err}"
        );
    }
    for (text, step_s) in [
        ("", defaults::ESKF_COVARIANCE_STEP_S),
        ("[eskf]\ncovariance_step_s = 0.0\n", 0.0),
        ("[eskf]\ncovariance_step_s = 0.1\n", 0.1),
    ] {
        let f = ConfigFile::parse(text, Path::new("a.toml")).unwrap();
        let cfg = f.validate().unwrap();
        assert_eq!(cfg.eskf.covariance_step_s.get(), step_s, "{text}");
    }
}

#[test]
fn a_gap_threshold_beyond_any_foot_imu_is_refused() {
    for (text, shown) in [
        ("[estimator]\nmax_dt_s = 1e9\n", "1e9"),
        ("[estimator]\nmax_dt_s = 1e-9\n", "1e-9"),
    ] {
        let f = ConfigFile::parse(text, Path::new("a.toml")).unwrap();
        let err = f.validate().unwrap_err().to_string();
        assert!(
            err.contains("estimator.max_dt_s") && err.contains(shown),
            "{text}: {err}"
        );
    }
    // A 400 Hz sensor's, and the shipped one.
    for text in [
        "[estimator]\nmax_dt_s = 0.01\n",
        "[estimator]\nmax_dt_s = 0.05\n",
    ] {
        assert!(
            ConfigFile::parse(text, Path::new("a.toml"))
                .unwrap()
                .validate()
                .is_ok()
        );
    }
}

#[test]
fn bad_values_name_key_and_value() {
    let f = ConfigFile::parse("[eskf]\nzupt_sd_m_s = -1.0\n", Path::new("a.toml")).unwrap();
    let err = with_path(f.validate().unwrap_err(), Path::new("a.toml")).to_string();
    assert!(err.contains("eskf.zupt_sd_m_s"), "{err}");
    assert!(err.contains("-1"), "{err}");
    assert!(err.contains("a.toml"), "{err}");

    let f = ConfigFile::parse("[heading]\ngrid_step_deg = 70.0\n", Path::new("a.toml")).unwrap();
    assert!(
        f.validate()
            .unwrap_err()
            .to_string()
            .contains("grid_step_deg")
    );

    // An angle key shows the degrees as written, not the radians it is kept in.
    for (section, key) in [
        ("heading", "sigma_deg"),
        ("heading", "stride_sigma_deg"),
        ("heading", "foot_axis_stride_max_deg"),
        ("model", "heading_offset_sd_deg"),
        ("model", "gyro_coupling_z_sd_deg"),
        ("alignment", "max_prior_rate_rad_s"),
    ] {
        let f = ConfigFile::parse(&format!("[{section}]\n{key} = -3.0\n"), Path::new("a.toml"))
            .unwrap();
        let err = f.validate().unwrap_err().to_string();
        assert!(err.contains(&format!("{section}.{key}")), "{err}");
        assert!(err.contains("-3") && !err.contains("-0.05"), "{err}");
    }

    // Positive but beyond what the quantity can be: refused, the value shown as written.
    for (section, key, v) in [
        ("eskf", "initial_tilt_sd_rad", "1e300"),
        ("estimator", "max_speed_m_s", "1e-9"),
        ("alignment", "gravity_m_s2", "1e6"),
        ("sensor", "max_gyro_bias_rad_s", "1e-12"),
        ("heading", "start_heading_deg", "1e300"),
        ("heading", "foot_axis_stride_max_deg", "120"),
        ("detector", "overdue_stride_factor", "1.05"),
        ("model", "accel_scale_factor", "-0.25"),
        ("model", "heading_offset_sd_deg", "1e300"),
        ("alignment", "max_prior_rate_rad_s", "20"),
    ] {
        let f =
            ConfigFile::parse(&format!("[{section}]\n{key} = {v}\n"), Path::new("a.toml")).unwrap();
        let err = f.validate().unwrap_err().to_string();
        assert!(err.contains(&format!("{section}.{key}")), "{err}");
        assert!(err.contains(v) && err.len() < 200, "{err}");
    }

    for v in ["0", "1", "101"] {
        let f = ConfigFile::parse(
            &format!("[heading]\nreacquire_strides = {v}\n"),
            Path::new("a.toml"),
        )
        .unwrap();
        let err = f.validate().unwrap_err().to_string();
        assert!(err.contains("heading.reacquire_strides"), "{err}");
        assert!(err.contains(v) && err.contains("2..=100"), "{err}");
    }

    for (key, values) in [
        ("max_bridge_s", ["-0.1", "2.0", "nan"]),
        ("max_fill_s", ["-0.1", "1.5", "nan"]),
    ] {
        for v in values {
            let f = ConfigFile::parse(&format!("[estimator]\n{key} = {v}\n"), Path::new("a.toml"))
                .unwrap();
            let err = f.validate().unwrap_err().to_string();
            assert!(
                err.contains(&format!("estimator.{key}")) && err.contains("[0, 1]"),
                "{err}"
            );
        }
    }

    for v in ["-0.01", "0.05"] {
        let f = ConfigFile::parse(
            &format!("[detector]\nlate_stance_min_s = {v}\n"),
            Path::new("a.toml"),
        )
        .unwrap();
        let err = f.validate().unwrap_err().to_string();
        assert!(
            err.contains("detector.late_stance_min_s")
                && err.contains(v)
                && err.contains("detector.min_stance_s]"),
            "{err}"
        );
    }

    let f = ConfigFile::parse("[detector]\nwindow = 0\n", Path::new("a.toml")).unwrap();
    assert!(
        f.validate()
            .unwrap_err()
            .to_string()
            .contains("detector.window")
    );
}

#[test]
fn daemon_runtime_dir_must_be_absolute() {
    let f = ConfigFile::parse(
        "[daemon]\nruntime_dir = \"run/corridor\"\n",
        Path::new("s.toml"),
    )
    .unwrap();
    let err = f.validate_daemon().unwrap_err().to_string();
    assert!(
        err.contains("daemon.runtime_dir")
            && err.contains("run/corridor")
            && err.contains("absolute"),
        "{err}"
    );
    let f = ConfigFile::parse(
        "[daemon]\nruntime_dir = \"/run/corridor\"\n",
        Path::new("s.toml"),
    )
    .unwrap();
    assert_eq!(
        f.validate_daemon().unwrap().runtime_dir.as_deref(),
        Some(Path::new("/run/corridor"))
    );
}

#[test]
fn an_empty_checkpoint_path_is_refused() {
    let f = ConfigFile::parse("[daemon]\ncheckpoint_path = \"\"\n", Path::new("s.toml")).unwrap();
    let err = f.validate_daemon().unwrap_err().to_string();
    assert!(
        err.contains("daemon.checkpoint_path") && err.contains("leave the key out"),
        "{err}"
    );
}

#[test]
fn daemon_section_is_validated() {
    let f = ConfigFile::parse("[daemon]\ndelivery = \"sometimes\"\n", Path::new("s.toml")).unwrap();
    assert!(
        f.validate()
            .unwrap_err()
            .to_string()
            .contains("daemon.delivery")
    );
    let f = ConfigFile::parse("[daemon]\ndomain = \"a b\"\n", Path::new("s.toml")).unwrap();
    assert!(
        f.validate()
            .unwrap_err()
            .to_string()
            .contains("daemon.domain")
    );
    // The longest domain the services accept passes, one more character does not (config
    // and `corridor serve` once disagreed: 64 against 48).
    let long = |n: usize| format!("[daemon]\ndomain = \"{}\"\n", "d".repeat(n));
    let max = crate::services::MAX_DOMAIN_LEN;
    let ok = ConfigFile::parse(&long(max), Path::new("s.toml")).unwrap();
    crate::services::Domain::new(&ok.validate_daemon().unwrap().domain).unwrap();
    let err = ConfigFile::parse(&long(max + 1), Path::new("s.toml"))
        .unwrap()
        .validate()
        .unwrap_err()
        .to_string();
    assert!(err.contains("daemon.domain") && err.contains("48"), "{err}");
    let f = ConfigFile::parse(
        "[daemon]\ndelivery = \"lossless\"\nchannel_capacity = 8\n",
        Path::new("s.toml"),
    )
    .unwrap();
    f.validate().unwrap();
    let d = f.validate_daemon().unwrap();
    assert!(d.lossless);
    assert_eq!(d.channel_capacity, 8);
    // A period no duration can hold is refused here, not where the daemon starts.
    for key in [
        "diagnostics_period_s",
        "stall_timeout_s",
        "producer_takeover_s",
    ] {
        let f =
            ConfigFile::parse(&format!("[daemon]\n{key} = 1e300\n"), Path::new("s.toml")).unwrap();
        let err = f.validate_daemon().unwrap_err().to_string();
        assert!(err.contains(&format!("daemon.{key}")), "{err}");
    }
}

#[test]
fn every_daemon_number_has_a_range_and_its_error_names_key_value_and_range() {
    use defaults::*;
    // A review: `health_period_s = 1e-9` was taken (a health line and diagnostics at every
    // IMU sample, a core spinning between them) and `channel_capacity = 16777216` too
    // (1.7 GB preallocated at start).
    let daemon = |body: String| {
        ConfigFile::parse(&format!("[daemon]\n{body}\n"), Path::new("s.toml"))
            .unwrap()
            .validate_daemon()
    };
    let periods = [
        (
            "bias_period_s",
            DAEMON_BIAS_PERIOD_MIN_S,
            DAEMON_OUTPUT_PERIOD_MAX_S,
        ),
        (
            "diagnostics_period_s",
            DAEMON_WAKE_S,
            DAEMON_OUTPUT_PERIOD_MAX_S,
        ),
        ("health_period_s", DAEMON_WAKE_S, DAEMON_HEALTH_PERIOD_MAX_S),
        (
            "checkpoint_period_s",
            DAEMON_WAKE_S,
            DAEMON_CHECKPOINT_PERIOD_MAX_S,
        ),
        ("stall_timeout_s", DAEMON_WAKE_S, DAEMON_STALL_TIMEOUT_MAX_S),
        (
            "producer_takeover_s",
            DAEMON_WAKE_S,
            DAEMON_PRODUCER_TAKEOVER_MAX_S,
        ),
    ];
    for (key, lo, hi) in periods {
        for ok in [lo, hi] {
            daemon(format!("{key} = {ok:?}")).unwrap_or_else(|e| panic!("{key} = {ok}: {e}"));
        }
        for (bad, shown) in [
            (lo * 0.99, format!("{}", lo * 0.99)),
            (hi * 1.01, format!("{}", hi * 1.01)),
            (1e-9, "1e-9".to_owned()),
            (0.0, "0".to_owned()),
        ] {
            let err = daemon(format!("{key} = {bad:?}")).unwrap_err().to_string();
            assert!(
                err.contains(&format!("`daemon.{key}` = {shown}:"))
                    && err.contains(&format!("[{lo}, {hi}] s")),
                "{key} = {bad}: {err}"
            );
        }
    }
    // The wake-up slice is the event waits'.
    assert_eq!(
        DAEMON_WAKE_S,
        crate::services::EVENT_WAIT_SLICE.as_secs_f64()
    );
    let max = DAEMON_CHANNEL_CAPACITY_MAX;
    assert_eq!(
        daemon(format!("channel_capacity = {max}"))
            .unwrap()
            .channel_capacity,
        max
    );
    for bad in [0, max + 1, 1 << 24, i64::MAX as usize] {
        let err = daemon(format!("channel_capacity = {bad}"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains(&format!("`daemon.channel_capacity` = {bad}:"))
                && err.contains(&format!("[1, {max}] samples")),
            "{bad}: {err}"
        );
    }
    // What the bound's documentation says it preallocates: about 100 bytes a slot, 55 MB.
    let slot = std::mem::size_of::<crate::wire::ImuSample>() + 16;
    assert!(slot <= 104 && max * slot <= 55_000_000, "{slot} B a slot");
}

#[test]
fn a_typical_bias_needs_its_sigma_and_must_lie_within_the_sensors_largest_bias() {
    let parse = |body: &str| {
        ConfigFile::parse(&format!("[alignment]\n{body}"), Path::new("t.toml"))
            .unwrap()
            .validate()
    };
    let c =
        parse("typical_gyro_bias_rad_s = [1e-3, -2e-3, 5e-3]\ntypical_gyro_bias_sd_rad_s = 4e-3\n")
            .unwrap();
    let t = c.alignment.typical_gyro_bias.unwrap();
    assert_eq!((t.rad_s, t.sd_rad_s.get()), ([1e-3, -2e-3, 5e-3], 4e-3));
    assert!(Config::default().alignment.typical_gyro_bias.is_none());
    for (body, key, value) in [
        // One without the other: the missing key is named.
        (
            "typical_gyro_bias_rad_s = [1e-3, -2e-3, 5e-3]\n",
            "alignment.typical_gyro_bias_sd_rad_s",
            "not given",
        ),
        (
            "typical_gyro_bias_sd_rad_s = 4e-3\n",
            "alignment.typical_gyro_bias_rad_s",
            "not given",
        ),
        // Beyond the sensor's largest bias (default 0.2 rad/s), or not a number.
        (
            "typical_gyro_bias_rad_s = [1e-3, 0.5, 5e-3]\ntypical_gyro_bias_sd_rad_s = 4e-3\n",
            "alignment.typical_gyro_bias_rad_s",
            "0.5",
        ),
        (
            "typical_gyro_bias_rad_s = [nan, 0.0, 0.0]\ntypical_gyro_bias_sd_rad_s = 4e-3\n",
            "alignment.typical_gyro_bias_rad_s",
            "NaN",
        ),
        (
            "typical_gyro_bias_rad_s = [0.0, 0.0, 0.0]\ntypical_gyro_bias_sd_rad_s = 0.0\n",
            "alignment.typical_gyro_bias_sd_rad_s",
            "0",
        ),
    ] {
        let err = parse(body).unwrap_err().to_string();
        assert!(err.contains(key) && err.contains(value), "{body}: {err}");
    }
    // Two or four axes are a TOML shape error, named with the key.
    let err = ConfigFile::parse(
        "[alignment]\ntypical_gyro_bias_rad_s = [1e-3, 2e-3]\n",
        Path::new("t.toml"),
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("typical_gyro_bias_rad_s"), "{err}");
}

#[test]
fn unknown_mode_is_rejected() {
    let err = ConfigFile::parse("[estimator]\nmode = \"magic\"\n", Path::new("m.toml"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("magic"), "{err}");
}
