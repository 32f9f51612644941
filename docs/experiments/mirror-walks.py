#!/usr/bin/env python3
"""The suite on its own walks seen in a mirror, or with the sensor mounted otherwise: a check that
nothing in the configuration or the estimator prefers one side (left turns over right ones, a
foot that toes out one way, a bias of one sign) or one mounting.

    python3 docs/experiments/mirror-walks.py      # from the repository root, release binary built

Each bundled walk is reflected in the vertical plane through its sensor's x and z axes: a
mirror-image walker with a mirror-image sensor. Rates are pseudovectors, so under the reflection
y -> -y of the body frame the gyro becomes (-gx, gy, -gz); the specific force becomes
(ax, -ay, az); the footprints (x, y) -> (x, -y); the start heading psi -> -psi on the same grid.
This is a physically valid walk (the sensor's own errors mirror with it: a bias, a clipped rail,
a misalignment), so a side-free estimator scores it as it scores the walk itself, up to its
arithmetic. `corridor eval` runs the mirrored suite (a copy of configs/eval/gdins.toml pointing
at mirrored copies of the logs, meta.json kept) and the script prints both suites' rows and
summaries side by side. OUT=dir keeps the mirrored suite's output (the temporary copies are
removed otherwise); BIN= another build's binary.

Since session 38 configs/gdins.toml holds the unit's typical bias (`alignment.typical_gyro_bias_rad_s`,
sensor axes), which this script does not mirror or turn with the samples: the mirrored runs
start from the prior of the unmirrored sensor (σ 4 mrad/s; with a rest, its mean is taken nearly
whole). The Rust tests (service/tests/mirror.rs, tests/tests/invariance.rs) turn it; for an exact
comparison here, point the suite at a copy of the configuration without those two keys.

TURN=1 turns the sensor on the shoe by 90° about its own z axis instead (every vector's
components in the new axes: x' = y, y' = -x; the gyro's rails stay on axes), and ROTATE=axis,deg
(e.g. ROTATE=x,30) by any angle about any of its axes, on the walks without samples at a rail of
the gyro or the accelerometer only (a rotated rail is no real sensor's): a mounting the walks were not recorded
with. The footprints and the start heading stay as they are.
"""
import json, math, os, re, shutil, subprocess, sys, tempfile

root = os.getcwd()
binary = os.environ.get("BIN", os.path.join(root, "target/release/corridor"))
tmp = tempfile.mkdtemp(prefix="mirror-walks-")
out = os.environ.get("OUT", os.path.join(tmp, "out"))
suite_path = os.path.join(root, "configs/eval/gdins.toml")
suite = open(suite_path).read()


TURN = os.environ.get("TURN") == "1"
# ROTATE=axis,deg: the sensor mounted turned by deg about its own axis (x, y or z): every vector
# and pseudovector alike, v' = Rᵀ·v. Walks with samples at the gyro's rail are left out (their
# clipping would lie on other axes than the sensor's rails, which no real sensor does).
ROTATE = os.environ.get("ROTATE")
if ROTATE:
    axis, deg = ROTATE.split(",")
    c, s_ = math.cos(math.radians(float(deg))), math.sin(math.radians(float(deg)))
    i = "xyz".index(axis)
    j, k = (i + 1) % 3, (i + 2) % 3
    R = [[0.0] * 3 for _ in range(3)]
    R[i][i] = 1.0
    R[j][j], R[j][k], R[k][j], R[k][k] = c, -s_, s_, c


def rotated(vals):
    # Rᵀ·v, printed with full precision
    v = [float(x) for x in vals]
    return [repr(sum(R[r][q] * v[r] for r in range(3))) for q in range(3)]


def clipped(src):
    """A sample at a rail of the gdins sensor (gyro about 8.7 rad/s, accelerometer 8 g = 78.45 m/s²;
    within 2 % of either)."""
    with open(src) as f:
        cols = f.readline().strip().split(",")
        rails = [(cols.index(c), 0.98 * 8.727) for c in ("gx_rad_s", "gy_rad_s", "gz_rad_s")]
        rails += [(cols.index(c), 0.98 * 78.45) for c in ("ax_m_s2", "ay_m_s2", "az_m_s2")]
        return any(abs(float(line.split(",")[i])) >= r for line in f for i, r in rails)


def neg(x):
    return x if x in ("", "NaN") else (x[1:] if x.startswith("-") else "-" + x)


def mirror_imu(src, dst):
    with open(src) as f, open(dst, "w") as g:
        header = f.readline()
        g.write(header)
        cols = header.strip().split(",")
        triples = [[cols.index(c) for c in ("gx_rad_s", "gy_rad_s", "gz_rad_s")],
                   [cols.index(c) for c in ("ax_m_s2", "ay_m_s2", "az_m_s2")]]
        if "mx_gauss" in cols:
            triples.append([cols.index(c) for c in ("mx_gauss", "my_gauss", "mz_gauss")])
        for line in f:
            v = line.rstrip("\n").split(",")
            for k, (x, y, z) in enumerate(triples):
                if ROTATE:
                    v[x], v[y], v[z] = rotated([v[x], v[y], v[z]])
                elif TURN:
                    # the sensor mounted turned 90° about its z axis: every vector's components
                    # in the new axes (x' = y, y' = −x)
                    v[x], v[y] = v[y], neg(v[x])
                elif k == 1:
                    v[y] = neg(v[y])  # the specific force, a vector
                else:
                    v[x], v[z] = neg(v[x]), neg(v[z])  # rates and field, pseudovectors
            g.write(",".join(v) + "\n")


def mirror_truth(src, dst):
    with open(src) as f, open(dst, "w") as g:
        header = f.readline()
        g.write(header)
        y = header.strip().split(",").index("y_m")
        for line in f:
            v = line.rstrip("\n").split(",")
            if not (TURN or ROTATE):
                v[y] = repr(-float(v[y]))
            g.write(",".join(v) + "\n")


base = os.path.dirname(suite_path)


def absolute(block, imu, truth):
    """A recording's block with its log, truth and configurations at `imu`, `truth` and their
    absolute paths (the suite's own are relative to it)."""
    b = block.replace(path_of(block, "imu"), imu).replace(path_of(block, "truth"), truth)
    for key in ("config", "baseline_config"):
        rel = re.search(key + r' = "([^"]+)"', b)
        if rel:
            b = b.replace(rel.group(0), f'{key} = "{os.path.normpath(os.path.join(base, rel.group(1)))}"')
    return b


def path_of(block, key):
    return re.search(key + r' = "([^"]+)"', block).group(1)


blocks = suite.split("[[recording]]")
mirrored = [blocks[0]]
kept = [blocks[0]]
for block in blocks[1:]:
    imu = os.path.normpath(os.path.join(base, path_of(block, "imu")))
    truth = os.path.normpath(os.path.join(base, path_of(block, "truth")))
    if ROTATE and clipped(imu):
        continue
    d = os.path.join(tmp, os.path.basename(os.path.dirname(imu)))
    os.makedirs(d)
    mirror_imu(imu, os.path.join(d, "imu.csv"))
    mirror_truth(truth, os.path.join(d, "ground_truth.csv"))
    meta = os.path.join(os.path.dirname(truth), "meta.json")
    if os.path.exists(meta):
        shutil.copy(meta, d)
    b = absolute(block, os.path.join(d, "imu.csv"), os.path.join(d, "ground_truth.csv"))
    if not (TURN or ROTATE):
        for key in ("start_heading_deg", "grid_deg"):
            m = re.search(key + r" = ([-\d.]+)", b)
            if m:
                b = b.replace(m.group(0), f"{key} = {-float(m.group(1))}")
    mirrored.append(b)
    kept.append(absolute(block, imu, truth))
mirrored_suite = os.path.join(tmp, "mirrored.toml")
open(mirrored_suite, "w").write("[[recording]]".join(mirrored))
plain_suite = os.path.join(tmp, "plain.toml")
open(plain_suite, "w").write("[[recording]]".join(kept))

runs = {}
other = "turned" if (TURN or ROTATE) else "mirrored"
for label, s, o in (("as recorded", plain_suite, os.path.join(tmp, "plain")), (other, mirrored_suite, out)):
    subprocess.run([binary, "eval", "--suite", s, "--out", o], check=True, capture_output=True)
    runs[label] = {r["recording"]: r for r in json.load(open(os.path.join(o, "results.json")))}


def pct(r, mode):
    return r[mode]["rms_pct"]


print(f"| recording | gait | baseline | baseline {other} | default | default {other} |")
print("|---|---|---|---|---|---|")
summary = {k: {"zupt_rest": [], "best_rest": []} for k in runs}
for name, r in runs["as recorded"].items():
    m = runs[other][name]
    cells = []
    for mode in ("zupt_rest", "best_rest"):
        for label, x in (("as recorded", r), (other, m)):
            v = pct(x, mode)
            cells.append(f"{v:.2f} %")
            if x["gait"] == "normal":
                summary[label][mode].append(v)
    print(f"| {name} | {r['gait']} | " + " | ".join(cells) + " |")


def med(v):
    v = sorted(v)
    n = len(v)
    return v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2])


for label in runs:
    b, d = summary[label]["zupt_rest"], summary[label]["best_rest"]
    worse = sum(1 for x, y in zip(b, d) if y > x + 0.05)
    print(f"{label}: normal gait ({len(d)}) default median {med(d):.3f} %, worst {max(d):.2f} %; "
          f"baseline median {med(b):.3f} %, worst {max(b):.2f} %; default worse than the baseline "
          f"by > 0.05 on {worse}")

if "OUT" not in os.environ:
    shutil.rmtree(tmp, ignore_errors=True)
