//! `corridor demo`: the results table, the diagnosis loop, the injected exp25 run, the second
//! sensor, and the same injected run through the daemon ([`super::demo_daemon`]).

use super::demo_daemon::demo_daemon;
use super::run::brief;
use anyhow::{Context, Result};
use clap::Args;
use corridor_service::runner::{self, RunOptions};
use corridor_shared::config::{BiasPrior, Config, ConfigFile, ConfigOverrides};
use corridor_shared::imu_csv::ImuCsvOptions;
use corridor_shared::injection::BiasInjection;
use std::path::{Path, PathBuf};

#[derive(Args, Debug)]
pub(super) struct DemoArgs {
    /// Repository root (where configs/ and tests/data/ are).
    #[arg(long, default_value = ".")]
    pub(super) root: PathBuf,
    /// Output directory.
    #[arg(long, default_value = "out/demo")]
    pub(super) out: PathBuf,
}

/// Runs the demo; fails when the daemon section finds a loss or a difference.
pub(super) fn demo(a: &DemoArgs) -> Result<()> {
    let suite = a.root.join("configs/eval/gdins.toml");
    if !suite.is_file() {
        anyhow::bail!(
            "{} not found: run the demo from the repository's root, or give it with --root",
            suite.display()
        );
    }
    let rows = corridor_service::suite::run_suite(&suite)?;
    let md = corridor_service::suite::markdown(&rows);
    corridor_client::say!(
        "# Results on the bundled recordings ({})\n",
        suite.display()
    );
    corridor_client::say_text(&md);
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let loops = corridor_service::suite::loops_markdown(
        &corridor_service::suite::run_loops(&suite, &a.out.join("diagnose"))?
            .all_or_first_failure()?,
    );
    corridor_client::say!(
        "\n# The loop: residual diagnosis from the paper's model (reports in {})\n\n{loops}",
        a.out.join("diagnose").display()
    );
    std::fs::write(a.out.join("results.md"), format!("{md}\n{loops}"))?;
    let data = a.root.join("tests/data/gdins_exp25_multi_corridor");
    let run_dir = a.out.join("exp25_injected");
    // The paper's injected bias; the daemon section below replays the same log with it.
    let injection = BiasInjection {
        constant_rad_s: [0.001, 0.001, 0.005],
        ..Default::default()
    };
    let opts = RunOptions {
        imu: data.join("imu.csv"),
        config: demo_exp25_config(&a.root)?,
        map: None,
        truth: Some(data.join("ground_truth.csv")),
        injection,
        plots: true,
        out_dir: run_dir.clone(),
        csv: ImuCsvOptions::default(),
        warm_start: None,
    };
    let s = runner::run(&opts)?;
    corridor_client::say!(
        "\n# exp25 with the injected bias [0.001, 0.001, 0.005] rad/s, no prior, mode {}\n",
        s.mode
    );
    corridor_client::say!("{}", serde_json::to_string_pretty(&brief(&s))?);
    corridor_client::say!("\nFigures and CSV files: {}", run_dir.display());
    let exp25 = opts;
    let offline = s;

    // A second sensor, irregular timing, loop-closure truth only.
    let data = a.root.join("tests/data/xio_ngimu_long_walk");
    let opts = RunOptions {
        imu: data.join("imu.csv"),
        config: Config::from_file(&a.root.join("configs/ngimu.toml"))?,
        map: None,
        truth: Some(data.join("ground_truth.csv")),
        injection: BiasInjection::default(),
        plots: false,
        out_dir: a.out.join("xio"),
        csv: ImuCsvOptions::default(),
        warm_start: None,
    };
    let s = runner::run(&opts)?;
    let e = s.eval.as_ref();
    corridor_client::say!(
        "\n# xio NGIMU long walk (~400 Hz, irregular timing, {} gaps > {} s): loop-closure error {:.3} m over {:.1} m walked (x-io's own ZUPT: 0.421 m)",
        s.gaps,
        opts.config.max_dt_s.get(),
        e.and_then(|e| e.loop_closure_error_m).unwrap_or(f64::NAN),
        e.map_or(f64::NAN, |e| e.traj_path_length_m),
    );

    // The same injected exp25 run through the daemon over iceoryx2.
    demo_daemon(&a.out, &exp25, &offline)
}

/// The configuration of the demo's exp25 runs (offline and through the daemon):
/// `configs/gdins.toml` without a gyro-bias prior, walking off at heading 0°.
fn demo_exp25_config(root: &Path) -> Result<Config> {
    let path = root.join("configs/gdins.toml");
    let overrides = ConfigOverrides {
        gyro_bias_prior: Some(BiasPrior::None),
        start_heading_deg: Some(0.0),
        ..Default::default()
    };
    Ok(overrides.validate(&ConfigFile::read(&path)?, &path)?)
}
