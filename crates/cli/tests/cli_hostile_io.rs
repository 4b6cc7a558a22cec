//! Hostile input files through the real binary (issue 28): `info` and `convert` on each
//! must exit 2 with one line on stderr, quickly, whatever the file claims or holds.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

/// Wall-clock bound of one run of the binary on hostile input. The reads themselves take
/// milliseconds; the margin is for process start-up on a loaded machine. A reader that
/// allocated what a header claims aborts, one that buffered an endless stream would run
/// out of memory or time.
const BUDGET: Duration = Duration::from_secs(3);

fn hostile_corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../geom/tests/corpus/hostile")
}

fn run(args: &[&str]) -> (Output, Duration) {
    let t = Instant::now();
    let out = Command::new(env!("CARGO_BIN_EXE_reconbench"))
        .args(args)
        .output()
        .expect("binary runs");
    (out, t.elapsed())
}

/// Exit code 2, one line on stderr naming the file, no raw control byte, in time.
fn check_refused(what: &str, out: &Output, took: Duration, name: &str) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{what}: {err}");
    assert!(!err.contains("panicked"), "{what}: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{what}: {err:?}");
    assert!(err.contains(name), "{what}: no file name in {err:?}");
    assert!(
        !err.trim_end().chars().any(char::is_control),
        "{what}: raw control character in {err:?}"
    );
    assert!(took < BUDGET, "{what} took {took:?}");
}

#[test]
fn info_and_convert_refuse_every_hostile_file_with_exit_2_and_one_line() {
    let out_dir = tempfile::tempdir().unwrap();
    let target = out_dir.path().join("out.ply");
    let mut n = 0;
    for entry in std::fs::read_dir(hostile_corpus()).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_str().unwrap().to_string();
        let p = path.to_str().unwrap();
        let (out, took) = run(&["info", p]);
        check_refused(&format!("info {name}"), &out, took, &name);
        let (out, took) = run(&["convert", p, target.to_str().unwrap()]);
        check_refused(&format!("convert {name}"), &out, took, &name);
        assert!(!target.exists(), "convert {name} wrote an output");
        n += 1;
    }
    assert!(n >= 10, "only {n} hostile files");
}

#[test]
fn info_refuses_a_huge_vertex_count_over_megabytes_of_zeros_before_allocating() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("zeros.ply");
    let mut f = std::fs::File::create(&path).unwrap();
    f.write_all(
        b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n\
          property float x\nproperty float y\nproperty float z\nend_header\n",
    )
    .unwrap();
    f.write_all(&vec![0u8; 5 << 20]).unwrap();
    drop(f);
    let (out, took) = run(&["info", path.to_str().unwrap()]);
    check_refused("info zeros.ply", &out, took, "zeros.ply");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("declares 4000000000 records of 12 bytes")
            && err.contains("only 5242880 bytes remain"),
        "{err}"
    );
}

/// A file name carrying an escape sequence is shown escaped, not sent to the terminal.
#[cfg(unix)]
#[test]
fn a_file_name_with_control_characters_is_escaped_in_the_message() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("evil\u{1b}[2J\u{7}.xyz");
    std::fs::write(&path, b"0 0 nope\n").unwrap();
    let (out, took) = run(&["info", path.to_str().unwrap()]);
    check_refused("info evil.xyz", &out, took, r"evil\x1b[2J\x07.xyz");
}

/// An endless stream of zeros behind a PLY header, read through a FIFO: refused from the
/// header (binary) or at the first line (ascii), not buffered.
#[cfg(unix)]
#[test]
fn info_refuses_an_endless_stream_of_zeros() {
    let dir = tempfile::tempdir().unwrap();
    for (name, encoding, count) in [
        ("stream.ply", "binary_little_endian", 4_000_000_000u64),
        ("stream_ascii.ply", "ascii", 3),
    ] {
        let path = dir.path().join(name);
        assert!(
            Command::new("mkfifo")
                .arg(&path)
                .status()
                .unwrap()
                .success()
        );
        let p = path.clone();
        let head = format!(
            "ply\nformat {encoding} 1.0\nelement vertex {count}\nproperty float x\n\
             property float y\nproperty float z\nend_header\n"
        );
        let writer = std::thread::spawn(move || {
            let mut f = std::fs::OpenOptions::new().write(true).open(&p).unwrap();
            let zeros = vec![0u8; 1 << 16];
            let mut sent = 0u64;
            if f.write_all(head.as_bytes()).is_ok() {
                while sent < 4 << 30 && f.write_all(&zeros).is_ok() {
                    sent += zeros.len() as u64;
                }
            }
            sent
        });
        let (out, took) = run(&["info", path.to_str().unwrap()]);
        check_refused(&format!("info {name}"), &out, took, name);
        let sent = writer.join().unwrap();
        assert!(sent < 64 << 20, "{name}: the binary read {sent} bytes");
    }
}
