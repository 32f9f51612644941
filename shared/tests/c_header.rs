//! The C header of the wire types: the committed `client/c/corridor_wire.h` equals the one
//! generated from the Rust definitions, and a C compiler accepts its static assertions on
//! every size, alignment and offset (so C sees the Rust layout).

use corridor_shared::wire_layout::{c_header, layouts};
use std::path::{Path, PathBuf};
use std::process::Command;

fn header_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../client/c/corridor_wire.h")
}

#[test]
fn committed_header_equals_the_generated_one() {
    let committed = std::fs::read_to_string(header_path()).unwrap_or_default();
    assert!(
        committed == c_header(),
        "client/c/corridor_wire.h is stale: regenerate it with \
         `cargo run -p corridor-client --bin corridor-wire -- c-header > client/c/corridor_wire.h`"
    );
}

#[test]
fn a_c_compiler_accepts_the_layout_assertions() {
    let dir = std::env::temp_dir().join(format!("corridor-eco-c-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // Uses every type, so each struct is complete and its assertions are evaluated.
    let mut program =
        String::from("#include \"corridor_wire.h\"\nint main(void) {\n    size_t n = 0;\n");
    for t in layouts() {
        program.push_str(&format!("    n += sizeof(corridor_{});\n", t.name));
    }
    program.push_str("    return n == 0;\n}\n");
    let src = dir.join("layout.c");
    std::fs::write(&src, program).unwrap();
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let out = Command::new(&cc)
        .args(["-std=c11", "-Wall", "-Werror", "-pedantic", "-c"])
        .arg("-I")
        .arg(header_path().parent().unwrap())
        .arg(&src)
        .arg("-o")
        .arg(dir.join("layout.o"))
        .output()
        .unwrap_or_else(|e| {
            panic!("{cc}: {e} (a C compiler is needed: apt-get install build-essential)")
        });
    let _ = std::fs::remove_dir_all(&dir);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
