"""The walks of `configs/eval/gdins.toml`, for the experiment scripts in this folder (run from the
repository root): (name, IMU CSV, truth CSV, start heading in degrees) of each recording, the
fast-gait ones left out unless asked for."""
import os, re


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
