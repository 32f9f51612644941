"""The ctypes mirrors equal the Rust wire types: sizes, alignments, field names, offsets,
element types, iceoryx2 type names, services and constants, as measured by the Rust code
(`corridor-wire layout`; the Rust test passes the JSON in CORRIDOR_LAYOUT_JSON)."""

import ctypes
import json
import os
import unittest

from corridor_client import services, wire
from corridor_client.services import QOS

CTYPE = {"u32": ctypes.c_uint32, "u64": ctypes.c_uint64, "f64": ctypes.c_double}


def rust_layout() -> dict:
    path = os.environ.get("CORRIDOR_LAYOUT_JSON")
    if not path:
        raise RuntimeError(
            "CORRIDOR_LAYOUT_JSON is not set: run the Python tests through "
            "`cargo test --workspace` (service/tests/python_client.rs) or set it to the output "
            "of `cargo run -p corridor-client --bin corridor-wire -- layout`"
        )
    with open(path) as f:
        return json.load(f)


class WireLayout(unittest.TestCase):
    def test_every_type_matches_the_rust_layout(self) -> None:
        layout = rust_layout()
        self.assertEqual(layout["service_version"], wire.SERVICE_VERSION)
        types = {t.__name__: t for t in wire.WIRE_TYPES}
        self.assertEqual(sorted(types), sorted(t["name"] for t in layout["types"]))
        for rt in layout["types"]:
            py = types[rt["name"]]
            with self.subTest(type=rt["name"]):
                self.assertEqual(py.type_name(), rt["type_name"])
                self.assertEqual(py.SERVICE, rt["service"])
                self.assertEqual(ctypes.sizeof(py), rt["size"])
                self.assertEqual(ctypes.alignment(py), rt["align"])
                self.assertEqual([f[0] for f in py._fields_], [f["name"] for f in rt["fields"]])
                for (name, ftype), rf in zip(py._fields_, rt["fields"]):
                    self.assertEqual(getattr(py, name).offset, rf["offset"], name)
                    self.assertEqual(getattr(py, name).size, rf["size"], name)
                    elem = getattr(ftype, "_type_", ftype) if rf["len"] > 1 else ftype
                    self.assertIs(elem, CTYPE[rf["ty"]], name)
                    self.assertEqual(getattr(ftype, "_length_", 1), rf["len"], name)
                self.assertIn(py, QOS)

    def test_constants_match(self) -> None:
        for name, value in rust_layout()["constants"].items():
            self.assertEqual(getattr(wire, name), value, name)

    def test_service_constants_match(self) -> None:
        for name, value in rust_layout()["service_constants"].items():
            self.assertEqual(getattr(services, name), value, name)


if __name__ == "__main__":
    unittest.main()
