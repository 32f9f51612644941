//! The suite file's reading and checks, recording by recording.

use super::*;

fn footprints(xy: &[(f64, f64)]) -> Vec<TruthPoint> {
    xy.iter()
        .enumerate()
        .map(|(i, &(x_m, y_m))| TruthPoint {
            t_s: i as f64,
            x_m,
            y_m,
            z_m: 0.0,
            stride: None,
            sample_index: None,
        })
        .collect()
}

#[test]
fn the_start_heading_is_the_first_real_stride_on_the_grid() {
    // A shuffle of 0.2 m first, then a stride 20° off the grid's 90° direction.
    let a = 110f64.to_radians();
    let t = footprints(&[(0.0, 0.0), (0.2, 0.0), (0.8 * a.cos(), 0.8 * a.sin())]);
    assert_eq!(start_heading_from_truth(&t, 0.0), Some(90.0));
    // A grid turned by 30°: the nearest of 30, 120, 210, 300° is 120°.
    assert_eq!(start_heading_from_truth(&t, 30.0), Some(120.0));
    // Walking along −x: 180°, not −180°.
    let back = footprints(&[(0.0, 0.0), (-1.0, 0.01)]);
    assert_eq!(start_heading_from_truth(&back, 0.0), Some(180.0));
    let back_low = footprints(&[(0.0, 0.0), (-1.0, -0.01)]);
    assert_eq!(start_heading_from_truth(&back_low, 0.0), Some(180.0));
    // No footprint 0.5 m away: nothing to take it from.
    assert_eq!(
        start_heading_from_truth(&footprints(&[(0.0, 0.0), (0.3, 0.1)]), 0.0),
        None
    );
    assert_eq!(start_heading_from_truth(&[], 0.0), None);
}

fn write_suite(dir: &Path, truth: &str, recording_extra: &str) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(dir.join("truth.csv"), truth).unwrap();
    // Named files must exist (their contents are not read here).
    std::fs::write(dir.join("imu.csv"), "").unwrap();
    std::fs::write(dir.join("c.toml"), "").unwrap();
    let suite = dir.join("suite.toml");
    std::fs::write(
        &suite,
        format!(
            "[[recording]]\nname = \"walk\"\nimu = \"imu.csv\"\ntruth = \"truth.csv\"\n\
             config = \"c.toml\"\n{recording_extra}"
        ),
    )
    .unwrap();
    suite
}

/// The suite of [`write_suite`], read: its one recording, or the error's text.
fn read_one(dir: &Path, truth: &str, extra: &str) -> Result<SuiteRecording, String> {
    read_suite(&write_suite(dir, truth, extra))
        .map(|f| f.recordings[0].clone())
        .map_err(|e| e.to_string())
}

#[test]
fn a_missing_file_is_named_by_its_key_before_any_run() {
    let dir = std::env::temp_dir().join(format!("corridor-suite-missing-{}", std::process::id()));
    let truth = "t_s,x_m,y_m,z_m\n0.0,0.0,0.0,0.0\n1.0,0.1,0.9,0.0\n";
    let err = read_one(
        &dir,
        truth,
        "start_heading_deg = 0.0\nbaseline_config = \"nope.toml\"\n",
    )
    .unwrap_err();
    assert!(
        err.contains("baseline_config = \"nope.toml\": no such file"),
        "{err}"
    );
    // A directory where a file belongs: named as one, with the suite file, the recording, the
    // key and the path (it was "no such file").
    std::fs::create_dir_all(dir.join("imu_dir")).unwrap();
    let suite = write_suite(&dir, truth, "start_heading_deg = 0.0\n");
    let text = std::fs::read_to_string(&suite)
        .unwrap()
        .replace("imu = \"imu.csv\"", "imu = \"imu_dir\"");
    std::fs::write(&suite, text).unwrap();
    let err = read_suite(&suite).unwrap_err().to_string();
    assert!(
        err.starts_with(&suite.display().to_string())
            && err.contains("recording walk: imu = \"imu_dir\": is a directory, not a file"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn hand_placed_strides_must_be_strides_of_the_truth() {
    let dir = std::env::temp_dir().join(format!("corridor-suite-hand-{}", std::process::id()));
    let truth = "t_s,x_m,y_m,z_m,stride,sample_index\n0.0,0,0,0,0,0\n1.0,0.8,0,0,1,200\n\
                 2.0,1.6,0,0,2,400\n";
    let hand = |list: &str| {
        read_one(
            &dir,
            truth,
            &format!("start_heading_deg = 0.0\nhand_placed_strides = {list}\n"),
        )
    };
    assert_eq!(hand("[2, 1]").unwrap().hand_placed_strides, vec![2, 1]);
    let err = hand("[1, 3]").unwrap_err();
    assert!(
        err.contains("hand_placed_strides: stride 3 is no stride of its truth"),
        "{err}"
    );
    let err = hand("[1, 1]").unwrap_err();
    assert!(err.contains("stride 1 is listed twice"), "{err}");
    // A truth without a stride column has no stride to name.
    let no_strides = "t_s,x_m,y_m,z_m\n0.0,0,0,0\n1.0,0.8,0,0\n";
    let err = read_one(
        &dir,
        no_strides,
        "start_heading_deg = 0.0\nhand_placed_strides = [1]\n",
    )
    .unwrap_err();
    assert!(err.contains("stride 1 is no stride of its truth"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn two_recordings_of_one_name_are_refused() {
    let dir = std::env::temp_dir().join(format!("corridor-suite-names-{}", std::process::id()));
    let truth = "t_s,x_m,y_m,z_m\n0.0,0.0,0.0,0.0\n1.0,0.1,0.9,0.0\n";
    let twice = "start_heading_deg = 0.0\n[[recording]]\nname = \"walk\"\nimu = \"imu.csv\"\n\
                 truth = \"truth.csv\"\nconfig = \"c.toml\"\nstart_heading_deg = 0.0\n";
    let err = read_one(&dir, truth, twice).unwrap_err();
    assert!(err.contains("two recordings are named \"walk\""), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_report_directory_stays_inside_and_two_recordings_never_share_one() {
    // The loop removes a recording's earlier report: a name with `..` or `/` reached
    // outside OUT/diagnose, and "a b" and "a_b" shared one directory.
    for (name, dir) in [
        ("exp17 rect loop small", "exp17_rect_loop_small"),
        ("../../home", ".._.._home"),
        ("..", "recording_.."),
        ("", "recording_"),
        ("a/b\\c", "a_b_c"),
    ] {
        assert_eq!(report_dir_name(name), dir, "{name:?}");
        assert!(
            !Path::new(&report_dir_name(name))
                .components()
                .any(|c| !matches!(c, std::path::Component::Normal(_)))
        );
    }
    let dir = std::env::temp_dir().join(format!("corridor-suite-dirs-{}", std::process::id()));
    let truth = "t_s,x_m,y_m,z_m\n0.0,0.0,0.0,0.0\n1.0,0.1,0.9,0.0\n";
    let one = |name: &str| {
        format!(
            "[[recording]]\nname = {name:?}\nimu = \"imu.csv\"\ntruth = \"truth.csv\"\n\
             config = \"c.toml\"\nstart_heading_deg = 0.0\n"
        )
    };
    let alike = format!("start_heading_deg = 0.0\n{}{}", one("a b"), one("a/b"));
    let err = read_one(&dir, truth, &alike).unwrap_err();
    assert!(
        err.contains("would share the report directory \"a_b\""),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_recording_without_start_heading_takes_it_from_its_truth() {
    let dir = std::env::temp_dir().join(format!("corridor-suite-file-{}", std::process::id()));
    let truth = "t_s,x_m,y_m,z_m\n0.0,0.0,0.0,0.0\n1.0,0.1,0.9,0.0\n2.0,0.2,2.3,0.0\n";
    let given = read_one(&dir, truth, "start_heading_deg = 0.0\n").unwrap();
    assert_eq!(given.start_heading, StartHeading::Given);
    assert_eq!(given.start_heading_deg, 0.0);
    let derived = read_one(&dir, truth, "").unwrap();
    assert_eq!(derived.start_heading, StartHeading::FirstStride);
    assert_eq!(derived.start_heading_deg, 90.0);
    // suspect_legs left out: the legs the meta.json beside the truth flags.
    let line = "t_s,x_m,y_m,z_m\n0,0,0,0\n1,1.4,0,0\n2,2.8,0,0\n3,4.2,0,0\n4,5.6,0,0\n5,7.0,0,0\n";
    let legs = |extra: &str| read_one(&dir, line, extra).unwrap().suspect_legs;
    assert!(legs("").is_empty());
    let meta = |legs: &str| {
        let json = format!(
            r#"{{"truth": {{"imu_consistency": {{"crude_ins_fit": {{"{FLAGGED_LEGS_KEY}": {legs}}}}}}}}}"#
        );
        std::fs::write(dir.join("meta.json"), json).unwrap();
    };
    meta("[5]");
    assert_eq!(legs(""), vec![5]);
    assert!(legs("suspect_legs = []\n").is_empty());
    meta("\"five\"");
    let e = read_one(&dir, line, "").unwrap_err();
    assert!(
        e.contains("recording walk: suspect_legs") && e.contains("meta.json"),
        "{e}"
    );
    // ... not JSON at all: an error naming the file, not an empty list.
    std::fs::write(dir.join("meta.json"), "{ not json").unwrap();
    let e = read_one(&dir, line, "").unwrap_err();
    assert!(
        e.contains("meta.json") && e.contains("suspect_legs = []"),
        "{e}"
    );
    // ... without the entry: none.
    std::fs::write(dir.join("meta.json"), r#"{"truth": {}}"#).unwrap();
    assert!(legs("").is_empty());
    // ... flagging a leg the truth does not have, or one before the first-leg alignment's
    // footprint: said, and the recording scored on every footprint (the flags are extra
    // information; a suite file's own `suspect_legs` are checked strictly, below).
    meta("[9]");
    assert!(legs("").is_empty());
    meta("[1]");
    assert!(legs("").is_empty());
    let e = read_one(&dir, line, "suspect_legs = [9]\n").unwrap_err();
    assert!(e.contains("9 is not a leg"), "{e}");
    // ... named by the stride number of the footprint each ends at: a walk surveyed at its
    // corners (strides 0, 12, 17, 24, 31, 38) flagging the leg that ends at stride 31; a
    // stride no footprint carries (5) is left out, not taken for a leg number, and does
    // not cost the others.
    let corners = "t_s,x_m,y_m,z_m,stride,sample_index\n0,0,0,0,0,0\n1,6,0,0,12,200\n\
                   2,6,4,0,17,400\n3,0,4,0,24,600\n4,0,0,0,31,800\n5,6,0,0,38,1000\n";
    meta("[31]");
    assert_eq!(read_one(&dir, corners, "").unwrap().suspect_legs, vec![4]);
    meta("[5, 31, 99]");
    assert_eq!(read_one(&dir, corners, "").unwrap().suspect_legs, vec![4]);
    std::fs::remove_file(dir.join("meta.json")).unwrap();
    // A truth without a stride: the error names the recording and the key.
    let short = "t_s,x_m,y_m,z_m\n0.0,0.0,0.0,0.0\n1.0,0.1,0.1,0.0\n";
    let e = read_one(&dir, short, "").unwrap_err();
    assert!(e.contains("recording walk: start_heading_deg"), "{e}");
    // Values no walk can have: named, with the recording.
    let e = read_one(&dir, truth, "start_heading_deg = nan\n").unwrap_err();
    assert!(e.contains("recording walk: start_heading_deg: NaN"), "{e}");
    let e = read_one(&dir, truth, "grid_deg = 1e300\n").unwrap_err();
    assert!(e.contains("grid_deg: 1e300"), "{e}");
    // A suite without recordings, or with an injection that is no bias: refused.
    let suite = dir.join("suite.toml");
    std::fs::write(&suite, "recording = []\n").unwrap();
    let e = read_suite(&suite).err().unwrap().to_string();
    assert!(e.contains("no [[recording]]"), "{e}");
    let text = std::fs::read_to_string(write_suite(&dir, truth, "")).unwrap();
    std::fs::write(
        &suite,
        format!("inject_gyro_bias_rad_s = [nan, 0.0, 0.0]\n{text}"),
    )
    .unwrap();
    let e = read_suite(&suite).err().unwrap().to_string();
    assert!(e.contains("inject_gyro_bias_rad_s: NaN"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_blank_name_or_one_that_splits_a_table_row_is_refused_naming_the_entry() {
    let dir = std::env::temp_dir().join(format!("corridor-suite-blank-{}", std::process::id()));
    let truth = "t_s,x_m,y_m,z_m\n0.0,0.0,0.0,0.0\n1.0,0.1,0.9,0.0\n";
    let suite = write_suite(&dir, truth, "start_heading_deg = 0.0\n");
    let first = std::fs::read_to_string(&suite).unwrap();
    for (name, why) in [
        ("", "must not be empty"),
        ("   ", "must not be empty"),
        ("a|b", "'|'"),
        ("a\nb", "control character"),
        // "walk" is the first recording's: this one would be a second row that looks the same.
        ("walk ", "white space"),
    ] {
        // The second of two recordings: the entry is named by its place and its log.
        let text = format!(
            "{first}[[recording]]\nname = {name:?}\nimu = \"imu.csv\"\ntruth = \"truth.csv\"\n\
             config = \"c.toml\"\nstart_heading_deg = 0.0\n"
        );
        std::fs::write(&suite, text).unwrap();
        let err = read_suite(&suite).unwrap_err().to_string();
        assert!(
            err.starts_with(&suite.display().to_string())
                && err.contains(&format!(
                    "[[recording]] 2 of 2 (imu = \"imu.csv\"): name = {name:?} "
                ))
                && err.contains(why),
            "{name:?}: {err}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
