//! Writing results safely and printing numbers plainly: every file kshell writes goes through
//! [`write_atomic`] (a temporary file in the same folder, renamed over the target, so a crash or
//! Ctrl-C never leaves a half-written material or curve), and every number in a CSV through
//! [`num`] (shortest round-trip digits, exponent form outside [1e-5, 1e16)).

use std::io::Write;
use std::path::{Path, PathBuf};

/// `s` as a TOML basic string. Rust's `{:?}` is not one: it writes `\u{302}` for a combining
/// mark (a decomposed "é" in a file name, a "F̂" in a note), which TOML readers refuse.
pub fn toml_string(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

/// The temporary file next to `path` that [`write_atomic`] writes first.
fn temporary_for(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".into());
    path.with_file_name(format!(".{name}.ks-tmp-{}", std::process::id()))
}

/// What `path` is when it exists and is not a regular file ("a character device", "a FIFO", …),
/// following symbolic links; `None` for a regular file or a path that does not exist. An output
/// is only ever a regular file: a rename over a device node or a FIFO would replace it.
pub fn special_kind(path: &Path) -> Option<&'static str> {
    let meta = std::fs::metadata(path).ok()?;
    let kind = meta.file_type();
    if kind.is_file() {
        return None;
    }
    if kind.is_dir() {
        return Some("a folder");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_char_device() {
            return Some("a character device");
        }
        if kind.is_block_device() {
            return Some("a block device");
        }
        if kind.is_fifo() {
            return Some("a FIFO (named pipe)");
        }
        if kind.is_socket() {
            return Some("a socket");
        }
    }
    Some("a special file")
}

/// Opens `tmp` as a new, empty file. A leftover of the same name (a killed run with the same
/// pid) is removed first, so the open never lands on an existing file, FIFO or device.
fn create_temporary(tmp: &Path) -> std::io::Result<std::fs::File> {
    let open = || {
        std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(tmp)
    };
    match open() {
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
            std::fs::remove_file(tmp)?;
            open()
        }
        other => other,
    }
}

/// Writes `contents` to `path` through a temporary file in the same folder and a rename: readers
/// see the old file or the new one, never a truncated one. The temporary file is removed on error.
/// A `path` that exists and is not a regular file (a device, a FIFO, a socket, a folder) is
/// refused with [`std::io::ErrorKind::InvalidInput`] and left as it is.
pub fn write_atomic(path: &Path, contents: impl AsRef<[u8]>) -> std::io::Result<()> {
    if let Some(kind) = special_kind(path) {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("is {kind}, not a regular file; outputs are written only to regular files or new paths"),
        ));
    }
    let tmp = temporary_for(path);
    let mut created = false;
    let result = (|| {
        let mut f = create_temporary(&tmp)?;
        created = true;
        f.write_all(contents.as_ref())?;
        f.sync_all()?;
        drop(f);
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() && created {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// A text input's contents: a regular file (not a FIFO, a device or a folder, which could block
/// or never end) of at most `max_bytes`, in UTF-8. The message says which rule was broken.
pub fn read_text(path: &Path, max_bytes: u64) -> Result<String, String> {
    let meta = std::fs::metadata(path).map_err(|e| e.to_string())?;
    if !meta.is_file() {
        return Err("not a regular file".into());
    }
    if meta.len() > max_bytes {
        return Err(format!(
            "{} bytes, more than the {} MiB allowed",
            meta.len(),
            max_bytes >> 20
        ));
    }
    let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    String::from_utf8(bytes).map_err(|_| "not UTF-8 text".to_string())
}

/// A number for a CSV or TOML value: the shortest digits that read back to the same `f64`, in
/// plain notation for magnitudes in [1e-5, 1e16) and exponent notation outside (never the
/// 300-digit expansion `{}` prints for 1e300).
pub fn num(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || !x.is_finite() || (1e-5..1e16).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// Significant digits of a number shown to a reader: enough for any lab value, few
/// enough to round away a unit conversion's last-digit noise (52 mm read as 0.052 m).
pub const SHOWN_DIGITS: usize = 12;

/// A number for a reader (not for reading back): rounded to [`SHOWN_DIGITS`] significant
/// digits, then printed as [`num`] prints it (`52`, not `52.00000000000001`).
pub fn shown(x: f64) -> String {
    if !x.is_finite() {
        return num(x);
    }
    let rounded = format!("{x:.prec$e}", prec = SHOWN_DIGITS - 1);
    num(rounded.parse().unwrap_or(x))
}

/// A TOML float with `decimals` fixed decimals, in TOML's own spellings where it is not finite
/// (`nan`, `inf`, `-inf`: Rust prints `NaN`, which no TOML reader takes).
pub fn toml_float(x: f64, decimals: usize) -> String {
    if x.is_nan() {
        "nan".into()
    } else if x.is_infinite() {
        if x > 0.0 { "inf" } else { "-inf" }.into()
    } else {
        format!("{x:.decimals$}")
    }
}

/// A table cell: `decimals` fixed decimals for magnitudes below 1e9, exponent form above (a
/// width typed as 1e300 prints as `1.0000e300`, not as 300 digits).
pub fn cell(x: f64, decimals: usize) -> String {
    if x.abs() < 1e9 || !x.is_finite() {
        format!("{x:.decimals$}")
    } else {
        format!("{x:.decimals$e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn toml_floats_read_back_even_where_not_finite() {
        for x in [1.25, f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let doc: toml::Table = format!("v = {}", toml_float(x, 4)).parse().unwrap();
            let v = doc["v"].as_float().unwrap();
            assert!(v == x || (v.is_nan() && x.is_nan()), "{x}: {v}");
        }
    }

    #[test]
    fn numbers_round_trip_in_few_characters() {
        for x in [
            0.0,
            1.0,
            -2.5,
            0.1 + 0.2,
            1e-300,
            1e300,
            -1.7976931348623157e308,
            5e-324,
            123456.789,
            1e-5,
            9.99e-6,
            1e16,
        ] {
            let s = num(x);
            assert_eq!(s.parse::<f64>().unwrap(), x, "{s}");
            assert!(s.len() <= 24, "{x}: {s}");
        }
        assert_eq!(num(1e300), "1e300");
        assert_eq!(num(0.25), "0.25");
        assert_eq!(num(2e-6), "2e-6");
        assert_eq!(cell(1e300, 4), "1.0000e300");
        assert_eq!(shown(0.052 * 1e3), "52");
        assert_eq!(shown(0.18e-3 * 1e3), "0.18");
        assert_eq!(shown(103.6), "103.6");
        assert_eq!(shown(1e300), "1e300");
        assert_eq!(shown(1.0 / 3.0), "0.333333333333");
        assert_eq!(cell(12.345678, 2), "12.35");
    }

    #[test]
    fn atomic_write_replaces_and_leaves_no_temporary() {
        let dir = std::env::temp_dir().join(format!("kshell-io-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("a.txt");
        write_atomic(&p, "first").unwrap();
        write_atomic(&p, "second").unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "second");
        let names: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        assert_eq!(names.len(), 1, "a temporary file was left behind");
        // a folder that does not exist: an error, and nothing created
        assert!(write_atomic(&dir.join("no/such/b.txt"), "x").is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn atomic_write_leaves_a_fifo_in_place() {
        let dir = std::env::temp_dir().join(format!("kshell-io-fifo-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let fifo = dir.join("out.toml");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if !made.is_ok_and(|st| st.success()) {
            eprintln!("no mkfifo on this machine: the FIFO case is not run");
            std::fs::remove_dir_all(&dir).unwrap();
            return;
        }
        let err = write_atomic(&fifo, "x").unwrap_err();
        assert_eq!(err.kind(), std::io::ErrorKind::InvalidInput);
        assert!(err.to_string().contains("a FIFO"), "{err}");
        assert_eq!(special_kind(&fifo), Some("a FIFO (named pipe)"));
        let names: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        assert_eq!(names.len(), 1, "a temporary file was left behind");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
