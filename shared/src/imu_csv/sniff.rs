//! Files that are not CSV text or not separated by commas, and bytes quoted in messages.
//!
//! A compressed file is known by its first bytes and named with the command that decompresses
//! it (a gzipped log was refused as a file whose lines end in CR alone, its bytes printed raw).
//! A quoted excerpt escapes control characters and bytes that are not UTF-8, so that a terminal
//! shows them rather than acting on them.

use std::borrow::Cow;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// When `line` has no comma but a semicolon or a tab, what the file looks like to its reader:
/// `"the row has semicolons and no comma: the file looks semicolon-separated, and corridor reads
/// comma-separated CSV"` (`what` is `row` or `header`). A semicolon-separated export (a
/// spreadsheet in a locale whose decimal mark is a comma) was refused as rows of "1 fields".
pub(super) fn other_separator(line: &str, what: &str) -> Option<String> {
    if line.contains(',') {
        return None;
    }
    let (plural, name) = if line.contains(';') {
        ("semicolons", "semicolon")
    } else if line.contains('\t') {
        ("tabs", "tab")
    } else {
        return None;
    };
    Some(format!(
        "the {what} has {plural} and no comma: the file looks {name}-separated, and corridor \
         reads comma-separated CSV"
    ))
}

/// A compressed format that a log may come in.
struct Compression {
    /// How the file is, after "the file is".
    name: &'static str,
    /// Its first bytes.
    magic: &'static [u8],
    /// The suffix its files carry.
    suffix: &'static str,
    /// The command that writes the decompressed content to standard output.
    command: &'static str,
}

const COMPRESSIONS: [Compression; 5] = [
    Compression {
        name: "gzip-compressed",
        magic: &[0x1f, 0x8b],
        suffix: "gz",
        command: "gunzip -c",
    },
    Compression {
        name: "xz-compressed",
        magic: &[0xfd, b'7', b'z', b'X', b'Z', 0x00],
        suffix: "xz",
        command: "unxz -c",
    },
    Compression {
        name: "zstd-compressed",
        magic: &[0x28, 0xb5, 0x2f, 0xfd],
        suffix: "zst",
        command: "zstd -dc",
    },
    Compression {
        name: "a zip archive",
        magic: b"PK\x03\x04",
        suffix: "zip",
        command: "unzip -p",
    },
    // "BZh" is text: it counts with the block size and the first block's magic after it (or
    // that of the end of an empty stream), see `is_bzip2`.
    Compression {
        name: "bzip2-compressed",
        magic: b"BZh",
        suffix: "bz2",
        command: "bunzip2 -c",
    },
];

/// Whether `head` starts as a bzip2 stream: `BZh`, the block size `1`-`9`, then the magic of
/// a block (π's digits) or of the stream's end (√π's).
fn is_bzip2(head: &[u8]) -> bool {
    match head.get(3..10) {
        Some([b'1'..=b'9', magic @ ..]) => {
            magic == b"1AY&SY" || magic == [0x17, 0x72, 0x45, 0x38, 0x50, 0x90]
        }
        _ => false,
    }
}

/// When the file at `path` starts with `head`, the first bytes of a compressed format: what
/// its header is, with the command that decompresses it (a header problem, after "header").
pub(super) fn compressed(head: &[u8], path: &Path) -> Option<String> {
    let c = COMPRESSIONS
        .iter()
        .find(|c| head.starts_with(c.magic) && (c.suffix != "bz2" || is_bzip2(head)))?;
    Some(format!(
        "is not text: the file is {} (decompress it first: {} {} > {})",
        c.name,
        c.command,
        shell_word(path),
        shell_word(&decompressed_path(path, c.suffix))
    ))
}

/// Where to write the decompressed file at `path`: without the format's `suffix`, ending in
/// `.csv` (`imu.csv.gz` and `imu.gz` to `imu.csv`), never the file itself (`imu.csv`, gzipped,
/// to `imu-decompressed.csv`).
fn decompressed_path(path: &Path, suffix: &str) -> PathBuf {
    let mut out = path.with_extension("").into_os_string();
    match path.extension() {
        Some(ext) if ext.eq_ignore_ascii_case(suffix) => {
            let stripped = Path::new(&out);
            if !stripped
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("csv"))
            {
                out.push(".csv");
            }
        }
        _ => out.push("-decompressed.csv"),
    }
    out.into()
}

/// `path` as one word of a shell command: single-quoted unless it is made of characters the
/// shell leaves alone.
fn shell_word(path: &Path) -> String {
    let text = path.display().to_string();
    let plain = |b: u8| b.is_ascii_alphanumeric() || b"._/-+,:@%".contains(&b);
    if !text.is_empty() && text.bytes().all(plain) {
        text
    } else {
        format!("'{}'", text.replace('\'', r"'\''"))
    }
}

/// How many first bytes of a compressed file [`first_bytes`] shows: the longest magic (xz's six)
/// and a little more.
const FIRST_BYTES: usize = 8;

/// The first bytes of a compressed file, to quote in a message: printable ASCII as it is, any
/// other byte as `\xNN` (the rest is no text: valid UTF-8 in it would be noise, or worse).
pub(super) fn first_bytes(bytes: &[u8]) -> String {
    let mut out = String::new();
    for &b in bytes.iter().take(FIRST_BYTES) {
        if b.is_ascii_graphic() || b == b' ' {
            out.push(char::from(b));
        } else {
            write!(out, "\\x{b:02x}").expect("writing to a String");
        }
    }
    out
}

/// `bytes` to quote in a message, at most `max` characters: the text as it is, but each
/// control character escaped (see [`escape_controls`]) and each byte that is not UTF-8 written
/// `\xNN` (a terminal would act on the former; a U+FFFD would say nothing of the latter). NULs
/// are left out: a UTF-16 header reads as its text. An escape is never cut.
pub(super) fn excerpt(bytes: &[u8], max: usize) -> String {
    let mut out = String::new();
    let mut left = max;
    // Appends a piece when it fits in the characters left; `false` once one did not.
    let mut put = |out: &mut String, piece: &str| {
        let n = piece.chars().count();
        let fits = n <= left;
        if fits {
            left -= n;
            out.push_str(piece);
        }
        fits
    };
    let mut piece = String::new();
    for chunk in bytes.utf8_chunks() {
        for c in chunk.valid().chars().filter(|&c| c != '\0') {
            piece.clear();
            push_escaped(&mut piece, c);
            if !put(&mut out, &piece) {
                return out;
            }
        }
        for b in chunk.invalid() {
            piece.clear();
            write!(piece, "\\x{b:02x}").expect("writing to a String");
            if !put(&mut out, &piece) {
                return out;
            }
        }
    }
    out
}

/// Appends `c` to `out`, escaped when it is a control character: `\t`, `\n` and `\r` by name,
/// another ASCII one as `\xNN`, one beyond ASCII (or an invisible one, [`is_invisible`]) as
/// `\u{NN}`.
fn push_escaped(out: &mut String, c: char) {
    match c {
        '\t' | '\n' | '\r' => write!(out, "{}", c.escape_default()),
        c if c.is_ascii_control() => write!(out, "\\x{:02x}", c as u32),
        c if c.is_control() || is_invisible(c) => write!(out, "{}", c.escape_unicode()),
        c => {
            out.push(c);
            Ok(())
        }
    }
    .expect("writing to a String");
}

/// Whether `c` is a Unicode format character (general category Cf: a byte-order mark, a
/// zero-width space or joiner, a soft hyphen, a direction mark or override) or a
/// non-breaking space: printed as it is, a message showed nothing, or a space, where it stood
/// (a BOM in the middle of a field quoted the value `"-0.3035"` as "not a number"), or
/// reordered the text after it.
fn is_invisible(c: char) -> bool {
    matches!(
        c,
        '\u{a0}'
            | '\u{ad}'
            | '\u{600}'..='\u{605}'
            | '\u{61c}'
            | '\u{6dd}'
            | '\u{70f}'
            | '\u{180e}'
            | '\u{200b}'..='\u{200f}'
            | '\u{202a}'..='\u{202f}'
            | '\u{2060}'..='\u{2064}'
            | '\u{2066}'..='\u{206f}'
            | '\u{feff}'
            | '\u{fff9}'..='\u{fffb}'
            | '\u{e0001}'
            | '\u{e0020}'..='\u{e007f}'
    )
}

/// `text` with each control character (and each invisible one, [`is_invisible`]) escaped
/// (`\t`, `\x1b`, `\u{85}`, `\u{feff}`), to quote in a message (a rejected row's value, a
/// ground-truth header); borrowed when it holds none.
pub(crate) fn escape_controls(text: &str) -> Cow<'_, str> {
    if !text.contains(|c: char| c.is_control() || is_invisible(c)) {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        push_escaped(&mut out, c);
    }
    Cow::Owned(out)
}
