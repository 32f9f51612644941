"""The Python client against a real `corridor serve` process (domain `eco_python`): a Python
producer replays exp36, a Python consumer receives every attitude sample, and the final bias
equals `corridor run` on the same CSV, bit for bit.

Needs CORRIDOR_BIN (the `corridor` binary) and CORRIDOR_ROOT (the repository); the Rust test
service/tests/python_client.rs sets both."""

import glob
import json
import os
import signal
import subprocess
import tempfile
import time
import unittest

from corridor_client import (
    AttitudeSample,
    BiasSample,
    Consumer,
    Domain,
    Producer,
    read_imu_csv,
    replay_csv,
    wire,
)

DOMAIN = "eco_python"


def env(name: str) -> str:
    value = os.environ.get(name)
    if not value:
        raise RuntimeError(f"{name} is not set: run through `cargo test --workspace`")
    return value


def clean_domain(name: str) -> None:
    prefix = f"corridor_{name}_"
    for d in ("/dev/shm", "/tmp/iceoryx2", "/tmp/iceoryx2/services"):
        for p in glob.glob(os.path.join(d, prefix + "*")):
            try:
                os.remove(p)
            except OSError:
                pass


class Daemon(unittest.TestCase):
    def setUp(self) -> None:
        self.corridor = env("CORRIDOR_BIN")
        root = env("CORRIDOR_ROOT")
        self.imu = os.path.join(root, "tests/data/gdins_exp36_corridor_out_and_back/imu.csv")
        self.config = os.path.join(root, "configs/gdins.toml")
        clean_domain(DOMAIN)
        self.daemon = subprocess.Popen(
            [self.corridor, "serve", "--domain", DOMAIN, "--delivery", "lossless",
             "--config", self.config],
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        )

    def tearDown(self) -> None:
        self.daemon.terminate()
        self.daemon.wait(timeout=60)

    def offline_final_bias(self) -> list:
        with tempfile.TemporaryDirectory(prefix="corridor-eco-py-") as out:
            subprocess.run(
                [self.corridor, "run", "--imu", self.imu, "--config", self.config,
                 "--out", out],
                check=True, stdout=subprocess.DEVNULL,
            )
            with open(os.path.join(out, "summary.json")) as f:
                return json.load(f)["bias_rad_s"]

    def test_python_producer_and_consumer_match_the_offline_run(self) -> None:
        domain = Domain(DOMAIN)
        attitude = Consumer(domain, AttitudeSample, "eco-py-attitude", timeout_s=30)
        bias = Consumer(domain, BiasSample, "eco-py-bias", timeout_s=30)
        producer = Producer(domain, "eco-py-producer", timeout_s=30)
        self.assertEqual(producer.delivery, "lossless")  # taken from the daemon
        producer.wait_for_daemon(30)

        attitudes = []
        biases = []

        def drain() -> None:
            for c, into in ((attitude, attitudes), (bias, biases)):
                while (v := c.try_recv()) is not None:
                    into.append(v)

        samples = list(read_imu_csv(self.imu))
        for s in samples:
            self.assertEqual(producer.send_sample(s), 1)
            drain()
        producer.finish()
        deadline = time.monotonic() + 60
        while not (attitudes and attitudes[-1].flags & wire.FLAG_END_OF_STREAM):
            self.assertLess(time.monotonic(), deadline, "no end-of-stream attitude")
            v = attitude.recv(1.0)
            if v is not None:
                attitudes.append(v)
        while not (biases and biases[-1].flags & wire.FLAG_END_OF_STREAM):
            self.assertLess(time.monotonic(), deadline, "no end-of-stream bias")
            v = bias.recv(1.0)
            if v is not None:
                biases.append(v)

        # Every attitude: one per sample, then the marker; no seq gap.
        self.assertEqual(len(attitudes), len(samples) + 1)
        self.assertEqual([a.seq for a in attitudes], list(range(len(samples) + 1)))
        self.assertEqual(attitude.missed, 0)
        self.assertEqual(
            [a.imu_seq for a in attitudes[:-1]], list(range(len(samples)))
        )
        # The final bias equals the offline run's, bit for bit.
        final = list(biases[-1].gyro_bias_rad_s)
        self.assertEqual(final, self.offline_final_bias())
        self.assertEqual(list(attitudes[-2].gyro_bias_rad_s), final)
        producer.close()
        self.assertEqual(producer.closes_unconfirmed, 0, "the daemon took the samples")
        for c in (attitude, bias):
            c.close()

    def test_the_driver_example_feeds_the_daemon(self) -> None:
        domain = Domain(DOMAIN)
        diagnostics = Consumer(domain, wire.Diagnostics, "eco-py-diag", timeout_s=30)
        example = os.path.join(env("CORRIDOR_ROOT"), "client/python/examples/driver_producer.py")
        out = subprocess.run(
            ["python3", example, "--domain", DOMAIN, "--rate-hz", "400", "--seconds", "0.5"],
            check=True, capture_output=True, text=True, timeout=120,
        )
        self.assertIn("sent 201 messages, 0 undelivered", out.stdout)
        self.assertEqual(self.until_received(diagnostics, 201), 201)
        diagnostics.close()

    def until_received(self, diagnostics: Consumer, n: int) -> int:
        """The daemon's `received` count once it reached `n` (within 60 s)."""
        deadline = time.monotonic() + 60
        received = 0
        while received < n:
            self.assertLess(time.monotonic(), deadline, f"daemon received {received}")
            d = diagnostics.recv(1.0)
            if d is not None:
                received = d.received
        return received

    def until_end_of_stream(self, bias: Consumer) -> None:
        """Reads `bias` until the daemon's end-of-stream bias (within 30 s)."""
        deadline = time.monotonic() + 30
        while True:
            self.assertLess(time.monotonic(), deadline, "no end-of-stream bias")
            b = bias.recv(1.0)
            if b is not None and b.flags & wire.FLAG_END_OF_STREAM:
                return

    def stop_the_driver_example(self, sig: int, code: int) -> None:
        """The driver example, stopped by `sig` mid-stream: it exits with `code` and ends its
        stream (the daemon publishes its end-of-stream bias)."""
        domain = Domain(DOMAIN)
        diagnostics = Consumer(domain, wire.Diagnostics, "eco-py-diag-sig", timeout_s=30)
        bias = Consumer(domain, BiasSample, "eco-py-bias-sig", timeout_s=30)
        example = os.path.join(env("CORRIDOR_ROOT"), "client/python/examples/driver_producer.py")
        # As a foreground process: a test run in the background (`nohup ... &`) hands its
        # children SIGINT ignored, and Python then never raises KeyboardInterrupt.
        driver = subprocess.Popen(
            ["python3", example, "--domain", DOMAIN, "--seconds", "60"],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        )
        self.until_received(diagnostics, 100)
        driver.send_signal(sig)
        out, err = driver.communicate(timeout=30)
        self.assertEqual(driver.returncode, code, err)
        self.assertIn("sent ", out)
        self.until_end_of_stream(bias)
        for c in (diagnostics, bias):
            c.close()

    def test_a_producer_left_by_an_error_ends_its_stream(self) -> None:
        # A log with a malformed row, replayed inside `with Producer(...)`: the error names the
        # row, and the stream ends (it stayed open, "running / phase: tracking", a review).
        domain = Domain(DOMAIN)
        bias = Consumer(domain, BiasSample, "eco-py-bias-err", timeout_s=30)
        with open(self.imu) as f:
            lines = f.read().splitlines()[:2000]
        fields = lines[1500].split(",")
        fields[2] = "x"
        lines[1500] = ",".join(fields)
        fd, bad = tempfile.mkstemp(suffix=".csv")
        with os.fdopen(fd, "w") as f:
            f.write("\n".join(lines) + "\n")
        with self.assertRaises(ValueError) as e:
            with Producer(domain, "eco-py-producer-err", timeout_s=30) as producer:
                producer.wait_for_daemon(30)
                replay_csv(producer, bad)
        os.remove(bad)
        self.assertIn(":1501: column gy_rad_s: 'x' is no number", str(e.exception))
        self.until_end_of_stream(bias)
        bias.close()

    def test_ctrl_c_stops_the_driver_example_and_ends_its_stream(self) -> None:
        # (iceoryx2's signal handler used to swallow it: the driver ran its 60 s.)
        self.stop_the_driver_example(signal.SIGINT, 130)

    def test_sigterm_stops_the_driver_example_and_ends_its_stream(self) -> None:
        # (It used to die at once, its stream left open.)
        self.stop_the_driver_example(signal.SIGTERM, 128 + signal.SIGTERM)


if __name__ == "__main__":
    unittest.main()
