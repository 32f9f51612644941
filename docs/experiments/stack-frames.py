#!/usr/bin/env python3
"""The largest stack frames of the estimator core's functions in a release binary.

A frame above a page (4 KB) is probed page by page at every call, and a frame larger than the
L1 data cache evicts the filter's own state: `Estimator::step` once had a 70 KB frame (copies of
the 7 KB filter built in its own frame by inlined rare paths), which cost 27 % of the core's
throughput (2.24 against 3.08 M samples/s for the build that set the 3 M target). Run it after a
change to the core:

    cargo build --release -p corridor-service --example core_once
    python3 docs/experiments/stack-frames.py [BINARY] [N]

It prints the N (default 20) largest frames of functions under `corridor_service::core`, from the
`sub $…, %rsp` of each function's prologue (objdump; the stack probe's `sub $…, %r11` counted
too). A function called at every sample should stay under a page; the large ones should be the
rare paths (a copy of the filter once per stance, gap or restart).
"""
import re
import subprocess
import sys

binary = sys.argv[1] if len(sys.argv) > 1 else "target/release/examples/core_once"
count = int(sys.argv[2]) if len(sys.argv) > 2 else 20
dis = subprocess.run(
    ["objdump", "-d", "--no-show-raw-insn", "-C", binary],
    capture_output=True, text=True, check=True,
).stdout
# Keyed on the address, so that instances of a generic function are told apart. A probed frame
# is `sub $N, %r11` (N whole pages), then a loop of `sub $0x1000, %rsp` down to it, then `sub $R,
# %rsp` for the rest: the loop's page is not added again.
frames, name, line_no, probing = {}, None, 0, False
for line in dis.splitlines():
    head = re.match(r"^([0-9a-f]+) <(.*)>:$", line)
    if head:
        name, line_no, probing = (head.group(1), head.group(2)), 0, False
        continue
    line_no += 1
    if name and line_no < 16:
        sub = re.search(r"sub\s+\$0x([0-9a-f]+),%(rsp|r11)", line)
        if sub:
            size, reg = int(sub.group(1), 16), sub.group(2)
            if reg == "r11":
                probing = True
            elif probing and size == 0x1000:
                continue
            frames[name] = frames.get(name, 0) + size
core = [(b, n[1]) for n, b in frames.items() if "corridor_service::core" in n[1]]
for size, fn in sorted(core, reverse=True)[:count]:
    print(f"{size:8d}  {fn[:140]}")
