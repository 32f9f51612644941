//! Runs the Python client's tests (`client/python/tests`, unittest) against this build: the
//! ctypes mirrors against the Rust layouts, and a Python producer and consumer against a real
//! `corridor serve` (domain `eco_python`). Needs python3 with the iceoryx2 0.10.0 wheel; without
//! it the test fails and says how to install it (`bash .ci/test` does).

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn python() -> String {
    std::env::var("PYTHON").unwrap_or_else(|_| "python3".into())
}

#[test]
fn python_client_tests_pass_against_the_daemon() {
    let py = python();
    let probe = Command::new(&py)
        .args([
            "-c",
            "import importlib.metadata as m; v = m.version('iceoryx2'); \
             assert v == '0.10.0', f'iceoryx2 {v}, expected 0.10.0'",
        ])
        .output();
    match probe {
        Ok(o) if o.status.success() => {}
        Ok(o) => panic!(
            "the Python client tests need the iceoryx2 0.10.0 wheel: \
             `{py} -m pip install iceoryx2==0.10.0` (or run `bash .ci/test`)\n{}",
            String::from_utf8_lossy(&o.stderr)
        ),
        Err(e) => panic!("{py}: {e} (the Python client tests need python3 >= 3.9)"),
    }
    let dir = std::env::temp_dir().join(format!("corridor-eco-py-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let layout = dir.join("layout.json");
    std::fs::write(&layout, corridor_shared::wire_layout::layout_json()).unwrap();
    let python_dir = root().join("client/python");
    let out = Command::new(&py)
        .args(["-m", "unittest", "discover", "-v", "-s"])
        .arg(python_dir.join("tests"))
        .current_dir(&python_dir)
        .env("PYTHONPATH", &python_dir)
        .env("CORRIDOR_BIN", env!("CARGO_BIN_EXE_corridor"))
        .env("CORRIDOR_ROOT", root())
        .env("CORRIDOR_LAYOUT_JSON", &layout)
        .output()
        .unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "Python client tests failed:\n{err}");
    // unittest reports on stderr; make sure the tests ran, not just an empty discovery.
    assert!(
        err.contains("Ran 11 tests") && err.contains("\nOK"),
        "{err}"
    );
}
