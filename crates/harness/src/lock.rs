//! A lock on a results file: two `reconbench run` writing the same results at once would
//! interleave and lose rows, so the second one refuses, naming the first one's PID. A
//! lock left by a run that was killed (its process is gone) is taken over.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::{HarnessError, Result};

/// Held while a run writes its results; released (the file removed) on drop.
#[derive(Debug)]
pub struct RunLock {
    path: PathBuf,
}

impl RunLock {
    /// Takes the lock file `path` (`<results file>.lock`), or explains who holds it.
    pub fn acquire(path: &Path) -> Result<Self> {
        for _ in 0..3 {
            match std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(path)
            {
                Ok(mut f) => {
                    writeln!(f, "{}", std::process::id()).map_err(|e| HarnessError::io(path, e))?;
                    return Ok(Self {
                        path: path.to_path_buf(),
                    });
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    let text = std::fs::read_to_string(path).unwrap_or_default();
                    if let Ok(pid) = text.trim().parse::<u32>()
                        && pid != std::process::id()
                        && process_alive(pid)
                    {
                        return Err(HarnessError::input(format!(
                            "{} is being written by another reconbench run (PID {pid}); wait for it to finish, \
                             use another --out, or delete {} if that process is not a reconbench run",
                            path.parent().unwrap_or(path).display(),
                            path.display()
                        )));
                    }
                    // Stale (its process is gone) or unreadable: take it over.
                    let _ = std::fs::remove_file(path);
                }
                Err(e) => return Err(HarnessError::io(path, e)),
            }
        }
        Err(HarnessError::failure(format!(
            "could not take the lock {}",
            path.display()
        )))
    }
}

impl Drop for RunLock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Whether a process with this PID exists (Linux: `/proc`; elsewhere assumed alive).
fn process_alive(pid: u32) -> bool {
    if cfg!(target_os = "linux") {
        Path::new(&format!("/proc/{pid}")).exists()
    } else {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_live_holder_refuses_and_a_stale_one_is_taken_over() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("results.jsonl.lock");
        drop(RunLock::acquire(&p).unwrap());
        assert!(!p.exists(), "released on drop");
        // A live foreign holder (PID 1 always exists) refuses.
        std::fs::write(&p, "1\n").unwrap();
        let e = RunLock::acquire(&p).unwrap_err().to_string();
        assert!(e.contains("PID 1"), "{e}");
        // A PID that cannot exist is stale.
        std::fs::write(&p, "4294967294\n").unwrap();
        let l = RunLock::acquire(&p).unwrap();
        assert_eq!(
            std::fs::read_to_string(&p).unwrap().trim(),
            std::process::id().to_string()
        );
        drop(l);
    }
}
