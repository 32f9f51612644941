//! The notes of a run: what the input did that a user should know about, said once in words.
//! `corridor run` prints them and `summary.json` carries them (`notes`): printed alone, they
//! were lost with the terminal (a review).

use super::Summary;
use std::collections::BTreeMap;

/// The notes on the run `s` summarises (empty when there is nothing to say).
pub(super) fn notes(s: &Summary) -> Vec<String> {
    let mut notes = Vec::new();
    if s.jittery_clock_samples > 0 {
        notes.push(format!(
            "the time stamps jitter (host arrival times?): {} samples integrated on a smoothed clock",
            s.jittery_clock_samples
        ));
    }
    if s.alignment_not_gravity > 0 {
        notes.push(format!(
            "{} {} not aligned on: {} specific force was no gravity (accelerations in g, a wrong scale or a broken accelerometer?); the log's warnings give the first",
            s.alignment_not_gravity,
            if s.alignment_not_gravity == 1 { "rest or stance was" } else { "rests or stances were" },
            if s.alignment_not_gravity == 1 { "its" } else { "their" }
        ));
    }
    if s.specific_force_off_gravity > 0 {
        let rest = s.rest_specific_force_m_s2.map_or_else(String::new, |f| {
            format!("the initial rest read {f:.2} m/s²; ")
        });
        let end = match (
            s.stance_specific_force_m_s2,
            s.specific_force_off_gravity_at_end,
        ) {
            (Some(f), true) => format!(
                "the quiet stances not back within 2.5 % of gravity by the end: {f:.2} m/s²"
            ),
            (Some(f), false) => {
                format!("the quiet stances back within 2.5 % of gravity by the end: {f:.2} m/s²")
            }
            (None, _) => "too few quiet stances for a median".to_string(),
        };
        notes.push(format!(
            "the specific force left gravity {} ({rest}{end}): the accelerometer's scale or units look wrong, and the distances walked with them; the log's warnings give the figure",
            match s.specific_force_off_gravity {
                1 => "once".to_string(),
                n => format!("{n} times"),
            }
        ));
    }
    if s.started_without_rest {
        notes.push(
            "no initial rest: aligned on a short first stance, without a rest-mean bias prior"
                .into(),
        );
    }
    if s.start_replayed_ms > 0 {
        notes.push(format!(
            "fast gait: the start went back {:.2} s, to the first stance the fast-gait rule takes (alignment.fast_gait_replay_s)",
            s.start_replayed_ms as f64 * 1e-3
        ));
    }
    if s.rest_prior_refused {
        notes.push(
            "the initial rest turned faster than a bias of this sensor can be (alignment.max_prior_rate_rad_s, sensor.max_gyro_bias_rad_s): a pivoting foot, no rest-mean bias prior"
                .into(),
        );
    }
    if s.initial_rest_moving_blocks > 0 {
        notes.push(format!(
            "the foot moved in {:.2} s of the initial rest (rocking, a weight shift): left out of the bias prior and the tilt",
            s.initial_rest_moving_blocks as f64 * crate::core::estimator::REST_BLOCK_S
        ));
    }
    if s.heading_aid == "none" && s.mode != "zupt" {
        // Nothing to observe the heading with: the never-held note below would blame a weave
        // or the start heading (a second-sensor review).
        notes.push(format!(
            "no heading aid (heading.source = \"none\" and no --map): the {} mode's heading was held by nothing but the start heading, and drifts as in the zupt mode",
            s.mode
        ));
    } else if let Some(note) = heading_never_held(s) {
        notes.push(note);
    }
    if let Some(d) = s.bias_from_typical_sd.filter(|&d| d > BIAS_NOTE_SD) {
        notes.push(format!(
            "the gyro bias estimate lies {d:.0} σ from this unit's typical bias (alignment.typical_gyro_bias_rad_s): check the IMU columns' axes and signs (a left-handed frame, a flipped axis), or the configuration is another unit's"
        ));
    }
    if s.velocity_resets + s.health_restores > 0 {
        // None on the 17 bundled walks; exp29 with its y axis negated: 10 resets and 21 restores
        // (configs/ngimu.toml, which has no typical bias for the note above), 21 % of path,
        // and nothing said (a second-sensor review).
        notes.push(format!(
            "the filter reset its velocity {} times and went back to its last healthy stance {} times: what it integrated contradicted the stances. Check the IMU columns' axes and signs (a left-handed frame, a flipped axis), samples at a rail (sensor ranges), or bursts of garbage in the log",
            s.velocity_resets, s.health_restores
        ));
    }
    let injecting =
        s.injected_gyro_bias_rad_s != [0.0; 3] || s.injected_gyro_bias_ramp_rad_s2 != [0.0; 3];
    if injecting && s.injected_rows == 0 {
        // (It ran with exit 0 and said nothing: a review.)
        notes.push(format!(
            "nothing was injected: the log ends before --inject-after-s {} s (counted from its first sample)",
            s.injected_after_s
        ));
    }
    let rejected: u64 = s.input_rows_rejected.values().sum();
    if rejected > 0 {
        // Said in the log's warnings and counted in summary.json; a note too, as for the
        // samples refused below (a review: 60 rows of NaN ran with `"notes": []`).
        notes.push(format!(
            "{rejected} {} of the CSV rejected, not read ({}): summary.json input_rows_rejected_examples names the first",
            if rejected == 1 { "row" } else { "rows" },
            counts_by_reason(&s.input_rows_rejected).join(", ")
        ));
    }
    let refused: u64 = s.samples_refused_counts.values().sum();
    if refused > 0 {
        // Never fused, and counted in summary.json; said here too (a review: 2 % of rows at
        // 1e30 ran with exit 0 and no note). None on the 17 bundled walks.
        notes.push(format!(
            "{refused} of {} samples refused, not fused ({}): summary.json samples_refused names the first",
            s.samples_read,
            counts_by_reason(&s.samples_refused_counts).join(", ")
        ));
    }
    if s.clipped_samples > 0 {
        notes.push(format!(
            "{} samples at a sensor rail (clipped); gyro peaks cut off by the rail put back: {} (not: {})",
            s.clipped_samples, s.clipped_peaks_restored, s.clipped_peaks_not_restored
        ));
    }
    notes
}

/// A final bias further than this many σ from the unit's typical one is worth a note (the 16
/// bundled walks end within 1 σ of it: its σ is their largest distance).
const BIAS_NOTE_SD: f64 = 5.0;

/// Stances a walk needs before a heading that no observation ever held is worth a note: ten
/// strides of each foot.
const HEADING_NOTE_MIN_STANCES: u64 = 20;

/// A walk whose heading no map direction ever took: every observation was refused (outside the
/// gate, unlikely, not straight), so nothing but the start heading fixed it. Said because the
/// footprints may then be off by a constant angle that nothing in the run shows (a start in a
/// weave anchors the start heading on a stride that runs off its corridor).
fn heading_never_held(s: &Summary) -> Option<String> {
    never_held_note(
        s.stances,
        s.heading_observations_used + s.stride_observations_used,
        &s.heading_observations_rejected,
        s.stride_observations_rejected,
    )
}

/// [`heading_never_held`] on the counts: the foot axes `refused` by reason, the stride
/// directions refused. A run with nothing to observe with (no heading aid, the ZUPT mode)
/// refuses none.
fn never_held_note(
    stances: u64,
    used: u64,
    refused: &BTreeMap<&'static str, u64>,
    strides_refused: u64,
) -> Option<String> {
    let reasons = counts_by_reason(refused);
    let tried = !reasons.is_empty() || strides_refused > 0;
    (used == 0 && tried && stances >= HEADING_NOTE_MIN_STANCES).then(|| {
        format!(
            "no heading observation was used in {stances} stances (foot axis refused: {}; stride directions refused: {strides_refused}): only the start heading fixed the heading, which may be off its corridors by more than the gate (a start in a weave, or a wrong --start-heading-deg)",
            if reasons.is_empty() {
                "none observed".to_string()
            } else {
                reasons.join(", ")
            },
        )
    })
}

/// The nonzero counts of `counts`, each as "reason n".
fn counts_by_reason(counts: &BTreeMap<&'static str, u64>) -> Vec<String> {
    counts
        .iter()
        .filter(|&(_, &n)| n > 0)
        .map(|(reason, n)| format!("{reason} {n}"))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::never_held_note;
    use std::collections::BTreeMap;

    #[test]
    fn a_heading_no_direction_ever_took_is_said_and_a_zupt_run_is_not() {
        let refused = BTreeMap::from([("outside_gate", 20), ("not_straight", 22), ("unlikely", 0)]);
        let note = never_held_note(49, 0, &refused, 41).expect("a note");
        assert!(
            note.contains("49 stances")
                && note.contains("not_straight 22, outside_gate 20;")
                && note.contains("refused: 41)"),
            "{note}"
        );
        // Strides alone observed (`heading.observations = "stride"`), every one refused.
        let none = BTreeMap::from([("outside_gate", 0), ("not_straight", 0)]);
        let note = never_held_note(49, 0, &none, 45).expect("a note");
        assert!(note.contains("foot axis refused: none observed;"), "{note}");
        // One observation used, a short log, or nothing to observe with (a ZUPT run counts
        // no refusal): no note.
        assert_eq!(never_held_note(49, 1, &refused, 41), None);
        assert_eq!(never_held_note(19, 0, &refused, 41), None);
        assert_eq!(never_held_note(49, 0, &none, 0), None);
    }
}
