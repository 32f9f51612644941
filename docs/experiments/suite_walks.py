"""The walks of `configs/eval/gdins.toml`, for the experiment scripts in this folder (run from the
repository root): (name, IMU CSV, truth CSV, start heading in degrees) of each recording, the
fast-gait ones left out unless asked for; and the helpers the clock-step scripts share."""
import csv, json, os, random, re, subprocess


def walks(root, fast=False):
    suite = open(os.path.join(root, "configs/eval/gdins.toml")).read()
    out = []
    for block in suite.split("[[recording]]")[1:]:
        name = re.search(r'name = "([^"]+)"', block).group(1)
        path = lambda key: re.search(key + r' = "([^"]+)"', block).group(1).replace("../../", root + "/")
        sh = re.search(r"start_heading_deg = ([-\d.]+)", block)
        gait = re.search(r'gait = "(\w+)"', block)
        if gait and gait.group(1) != "normal" and not fast:
            continue
        out.append((name, path("imu"), path("truth"), float(sh.group(1)) if sh else 0.0))
    return out


def stamp(row, dt):
    """A CSV row with its time `dt` later."""
    t, rest = row.split(",", 1)
    return repr(float(t) + dt) + "," + rest


def places(name, rows, estimates_csv):
    """Where `clock-steps.py` and `clock-steps-back.py` put a step in a walk's rows: 30, 50 and
    70 % of the log plus a fixed pseudo-random offset of up to 1 s, and the stance ends of the
    uncut run (its `estimates.csv`) nearest 30 and 70 %: (label, row index) each."""
    ts = [float(r.split(",", 1)[0]) for r in rows]
    est = list(csv.DictReader(open(estimates_csv)))
    ends = [float(est[i]["t_s"]) for i in range(1, len(est))
            if est[i - 1]["stance"] == "1" and est[i]["stance"] == "0"]
    out = []
    for pos in (0.3, 0.5, 0.7):
        random.seed(f"{name}/{pos}")
        out.append((f"{pos}", int(len(rows) * pos) + random.randint(0, 200)))
    for pos in (0.3, 0.7):
        t_end = min(ends, key=lambda e: abs(e - (ts[0] + pos * (ts[-1] - ts[0]))))
        out.append((f"end {pos}", min(range(len(ts)), key=lambda i: abs(ts[i] - t_end))))
    return out


def footprint_rms(binary, config, imu, truth, sh, out):
    """`corridor run` of one log: its footprint RMS, % of path (None when it failed); its
    estimates are left in `out`."""
    subprocess.run([binary, "run", "--imu", imu, "--truth", truth, "--config", config,
                    "--start-heading-deg", str(sh), "--out", out], capture_output=True)
    try:
        return json.load(open(os.path.join(out, "summary.json")))["eval"]["rms_error_pct_of_path"]
    except (OSError, KeyError, TypeError, ValueError):
        return None
