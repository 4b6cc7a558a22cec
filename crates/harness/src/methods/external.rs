//! External programs as methods: `external` (a reconstructor), `external-normals` and
//! `external-filter`. An experiment names a command template; the worker writes the
//! cell's cloud to a scratch directory in the format the program wants, runs the command,
//! and reads what it wrote with the project's readers. The run is timed like any method
//! and is stopped with the cell (time budget, cancellation): the program runs in a process
//! group of its own that the worker kills.
//!
//! ```toml
//! [[methods]]
//! name = "external"
//! label = "Open3D BPA"
//! params = { command = "python3 scripts/peers/open3d_bpa.py {input} {output} --radius {radius}", input = "ply", radius = [0.01, 0.02] }
//! ```
//!
//! Placeholders: `{input}`, `{output}` (quoted paths), `{dir}` (the scratch directory),
//! `{seed}`, `{threads}` (the cell's thread count) and `{NAME}` for every other parameter
//! (numbers, strings, lists joined by commas); other parameters sweep like any method's.

use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use reconbench_geom::PointCloud;
use reconbench_geom::io::{self, Format, WriteOptions};
use reconbench_geom::method::{
    Diagnostic, Diagnostics, Filter, Filtered, MethodError, NormalEstimator, Normals,
    Reconstruction, Reconstructor, RunCtx,
};
use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::entry::{Built, MethodEntry, MethodKind, ParamDoc, Unit, custom};

/// Bytes of the program's stderr kept for failure messages.
const STDERR_TAIL: usize = 4096;

/// Parameters of an external method. Keys other than the named fields are the program's
/// own parameters, substituted into `{NAME}` placeholders.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ExternalParams {
    /// Command template, run by `sh -c` from the current directory.
    pub command: String,
    /// File the program reads: `ply` (positions, and normals when the cloud has them),
    /// `ply-normals` (fails without normals), `xyz` or `off`.
    pub input: String,
    /// Extension of the file the program writes (`ply`, `obj`, `off`, `stl`, `xyz`).
    pub output: String,
    /// Own time limit in seconds (0 = the cell's budget only).
    pub timeout_s: f64,
    /// Virtual memory limit of the program in MiB (`ulimit -v`; 0 = none).
    pub memory_mib: u64,
    /// For `external-normals`: whether the program orients its normals consistently.
    pub oriented: bool,
    /// The program's own parameters.
    #[serde(flatten)]
    pub args: BTreeMap<String, Value>,
}

impl Default for ExternalParams {
    fn default() -> Self {
        Self {
            command: String::new(),
            input: "ply".into(),
            output: "ply".into(),
            timeout_s: 0.0,
            memory_mib: 0,
            oriented: false,
            args: BTreeMap::new(),
        }
    }
}

const DOCS: &[ParamDoc] = &[
    ParamDoc::new(
        "command",
        Unit::None,
        "sh command template: {input} {output} {dir} {seed} {threads} and {NAME} of the other parameters",
    ),
    ParamDoc::new(
        "input",
        Unit::Choice,
        "file written for the program: ply (default), ply-normals, xyz, off",
    ),
    ParamDoc::new(
        "output",
        Unit::Choice,
        "extension of the file the program writes: ply (default), obj, off, stl, xyz",
    ),
    ParamDoc::new(
        "timeout_s",
        Unit::Seconds,
        "the program's own time limit (0 = the cell's)",
    ),
    ParamDoc::new(
        "memory_mib",
        Unit::MiB,
        "virtual memory limit of the program (ulimit -v; 0 = none)",
    ),
    ParamDoc::new(
        "oriented",
        Unit::Flag,
        "external-normals: the program orients its normals consistently",
    ),
];

/// A validated external command.
#[derive(Debug, Clone)]
pub struct External {
    name: &'static str,
    params: ExternalParams,
    input: Format,
    want_normals: bool,
    output: Format,
}

fn bad(name: &str, message: impl Into<String>) -> MethodError {
    MethodError::InvalidParameter {
        name: name.into(),
        message: message.into(),
    }
}

impl External {
    /// Checks the template and formats.
    pub fn new(name: &'static str, params: ExternalParams) -> Result<Self, MethodError> {
        if params.command.trim().is_empty() {
            return Err(bad(
                "command",
                "an external method needs a command template",
            ));
        }
        let (input, want_normals) = match params.input.as_str() {
            "" | "ply" => (Format::Ply, false),
            "ply-normals" => (Format::Ply, true),
            "xyz" => (Format::Xyz, false),
            "off" => (Format::Off, false),
            other => {
                return Err(bad(
                    "input",
                    format!("unknown input format '{other}' (ply, ply-normals, xyz, off)"),
                ));
            }
        };
        let output = match params.output.as_str() {
            "" | "ply" => Format::Ply,
            "obj" => Format::Obj,
            "off" => Format::Off,
            "stl" => Format::Stl,
            "xyz" => Format::Xyz,
            other => {
                return Err(bad(
                    "output",
                    format!("unknown output format '{other}' (ply, obj, off, stl, xyz)"),
                ));
            }
        };
        if !(params.timeout_s.is_finite() && params.timeout_s >= 0.0) {
            return Err(bad("timeout_s", "must be a finite number >= 0"));
        }
        for ph in placeholders(&params.command) {
            let known = matches!(ph.as_str(), "input" | "output" | "dir" | "seed" | "threads")
                || params.args.contains_key(&ph);
            if !known {
                return Err(bad(
                    "command",
                    format!("placeholder {{{ph}}} is neither built in nor a parameter"),
                ));
            }
        }
        Ok(Self {
            name,
            params,
            input,
            want_normals,
            output,
        })
    }

    /// Writes `cloud`, runs the program and returns the path of what it wrote (inside
    /// `scratch`), with its wall time.
    fn run(
        &self,
        cloud: &PointCloud,
        ctx: &RunCtx,
        scratch: &Scratch,
    ) -> Result<(PathBuf, f64), MethodError> {
        if self.want_normals && cloud.normals().is_none() {
            return Err(MethodError::InvalidInput(format!(
                "{}: input = \"ply-normals\" but the cloud has no normals (add a normal step before it)",
                self.name
            )));
        }
        let input = scratch.0.join(format!("input.{}", ext(self.input)));
        let output = scratch.0.join(format!("output.{}", ext(self.output)));
        io::write_cloud_with(&input, cloud, self.input, &WriteOptions::default())?;
        let cmd = self.substitute(&input, &output, &scratch.0, ctx);
        let t0 = Instant::now();
        run_command(&cmd, self.params.memory_mib, self.params.timeout_s, ctx)?;
        let seconds = t0.elapsed().as_secs_f64();
        if !output.is_file() {
            return Err(MethodError::Failed(format!(
                "external command wrote no output file {} (command: {cmd})",
                output.display()
            )));
        }
        Ok((output, seconds))
    }

    fn substitute(&self, input: &Path, output: &Path, dir: &Path, ctx: &RunCtx) -> String {
        let threads = std::env::var("RAYON_NUM_THREADS").unwrap_or_else(|_| "1".into());
        let mut out = String::with_capacity(self.params.command.len() + 64);
        let mut rest = self.params.command.as_str();
        while let Some(i) = rest.find('{') {
            out.push_str(&rest[..i]);
            let after = &rest[i + 1..];
            match after.find('}') {
                Some(j) if is_name(&after[..j]) => {
                    let key = &after[..j];
                    out.push_str(&match key {
                        "input" => quote(input),
                        "output" => quote(output),
                        "dir" => quote(dir),
                        "seed" => ctx.seed.to_string(),
                        "threads" => threads.clone(),
                        k => value_text(&self.params.args[k]),
                    });
                    rest = &after[j + 1..];
                }
                _ => {
                    out.push('{');
                    rest = after;
                }
            }
        }
        out.push_str(rest);
        out
    }
}

fn is_name(s: &str) -> bool {
    !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// The `{NAME}` placeholders of a template.
fn placeholders(t: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = t;
    while let Some(i) = rest.find('{') {
        let after = &rest[i + 1..];
        match after.find('}') {
            Some(j) if is_name(&after[..j]) => {
                out.push(after[..j].to_string());
                rest = &after[j + 1..];
            }
            _ => rest = after,
        }
    }
    out
}

fn value_text(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        Value::Array(a) => a.iter().map(value_text).collect::<Vec<_>>().join(","),
        Value::Null => String::new(),
        other => other.to_string(),
    }
}

fn quote(p: &Path) -> String {
    format!("'{}'", p.display().to_string().replace('\'', r"'\''"))
}

fn ext(f: Format) -> &'static str {
    match f {
        Format::Ply => "ply",
        Format::Obj => "obj",
        Format::Off => "off",
        Format::Stl => "stl",
        Format::Xyz => "xyz",
        Format::Pts => "pts",
        Format::M => "m",
    }
}

/// A scratch directory removed on drop.
struct Scratch(PathBuf);

impl Scratch {
    fn new() -> Result<Self, MethodError> {
        static NEXT: AtomicU64 = AtomicU64::new(0);
        let dir = std::env::temp_dir().join(format!(
            "reconbench-external-{}-{}",
            std::process::id(),
            NEXT.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::create_dir_all(&dir)
            .map_err(|e| MethodError::Failed(format!("cannot create {}: {e}", dir.display())))?;
        Ok(Self(dir))
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Whether the template is one simple command, so `exec` can replace the shell by it.
fn is_simple(cmd: &str) -> bool {
    !cmd.chars()
        .any(|c| matches!(c, ';' | '&' | '|' | '(' | ')' | '<' | '>' | '`' | '\n'))
}

/// Runs `cmd` under `sh -c` in its own process group, polling the run context; kills
/// the group when the context stops or the own time limit passes.
fn run_command(
    cmd: &str,
    memory_mib: u64,
    timeout_s: f64,
    ctx: &RunCtx,
) -> Result<(), MethodError> {
    let mut script = String::new();
    if memory_mib > 0 {
        script.push_str(&format!("ulimit -v {} || exit 125; ", memory_mib * 1024));
    }
    if is_simple(cmd) {
        script.push_str("exec ");
    }
    script.push_str(cmd);
    // `setpriv --pdeathsig` (util-linux) kills the program if the worker itself is
    // killed (the runner's timeout or memory limit), where available.
    let setpriv = Path::new("/usr/bin/setpriv");
    let mut command = if setpriv.is_file() {
        let mut c = Command::new(setpriv);
        c.args(["--pdeathsig", "KILL", "sh", "-c", &script]);
        c
    } else {
        let mut c = Command::new("sh");
        c.args(["-c", &script]);
        c
    };
    use std::os::unix::process::CommandExt;
    let mut child = command
        .process_group(0)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| {
            MethodError::Failed(format!("cannot start sh for the external command: {e}"))
        })?;
    let pgid = child.id();
    let mut err = child.stderr.take();
    let reader = std::thread::spawn(move || {
        let mut buf = Vec::new();
        if let Some(e) = err.as_mut() {
            let _ = e.read_to_end(&mut buf);
        }
        let start = buf.len().saturating_sub(STDERR_TAIL);
        String::from_utf8_lossy(&buf[start..]).into_owned()
    });
    let t0 = Instant::now();
    let own = (timeout_s > 0.0).then(|| Duration::from_secs_f64(timeout_s));
    let kill = || {
        let _ = Command::new("kill")
            .args(["-KILL", "--", &format!("-{pgid}")])
            .stderr(Stdio::null())
            .status();
    };
    let status = loop {
        match child.try_wait() {
            Ok(Some(st)) => break st,
            Ok(None) => {}
            Err(e) => return Err(MethodError::Failed(format!("waiting for the command: {e}"))),
        }
        if let Err(e) = ctx.checkpoint() {
            kill();
            let _ = child.wait();
            return Err(e);
        }
        if own.is_some_and(|d| t0.elapsed() > d) {
            kill();
            let _ = child.wait();
            let tail = reader.join().unwrap_or_default();
            return Err(MethodError::Failed(format!(
                "external command exceeded its timeout_s = {timeout_s}{}",
                tail_text(&tail)
            )));
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    // Children the program left in its group go with it.
    kill();
    let tail = reader.join().unwrap_or_default();
    if !status.success() {
        return Err(MethodError::Failed(format!(
            "external command failed ({status}): {cmd}{}",
            tail_text(&tail)
        )));
    }
    Ok(())
}

fn tail_text(tail: &str) -> String {
    let t = tail.trim();
    if t.is_empty() {
        String::new()
    } else {
        format!("; stderr: {t}")
    }
}

fn unreadable(what: &str, path: &Path, e: impl std::fmt::Display) -> MethodError {
    MethodError::Failed(format!(
        "external command's output {} is not a readable {what}: {e}",
        path.display()
    ))
}

fn timed(seconds: f64) -> Diagnostics {
    let mut d = Diagnostics::new();
    d.insert("external_s".into(), Diagnostic::Number(seconds));
    d
}

impl Reconstructor for External {
    fn name(&self) -> &str {
        self.name
    }

    fn reconstruct(
        &self,
        cloud: &PointCloud,
        ctx: &mut RunCtx,
    ) -> Result<Reconstruction, MethodError> {
        let scratch = Scratch::new()?;
        let (out, s) = ctx.phase("external", || self.run(cloud, ctx, &scratch))?;
        let mesh = io::read_mesh_as(&out, self.output).map_err(|e| unreadable("mesh", &out, e))?;
        Ok(Reconstruction {
            mesh,
            refused: Vec::new(),
            diagnostics: timed(s),
        })
    }
}

impl NormalEstimator for External {
    fn name(&self) -> &str {
        self.name
    }

    fn estimate(&self, cloud: &PointCloud, ctx: &mut RunCtx) -> Result<Normals, MethodError> {
        let scratch = Scratch::new()?;
        let (out, s) = ctx.phase("external", || self.run(cloud, ctx, &scratch))?;
        let got = io::read_cloud_as(&out, self.output).map_err(|e| unreadable("cloud", &out, e))?;
        let Some(n) = got.normals() else {
            return Err(unreadable("cloud with normals", &out, "no normals in it"));
        };
        if n.len() != cloud.len() {
            return Err(unreadable(
                "cloud",
                &out,
                format!("{} normals for {} input points", n.len(), cloud.len()),
            ));
        }
        Ok(Normals {
            normals: n.to_vec(),
            oriented: self.params.oriented,
            diagnostics: timed(s),
        })
    }
}

impl Filter for External {
    fn name(&self) -> &str {
        self.name
    }

    fn filter(&self, cloud: &PointCloud, ctx: &mut RunCtx) -> Result<Filtered, MethodError> {
        let scratch = Scratch::new()?;
        let (out, s) = ctx.phase("external", || self.run(cloud, ctx, &scratch))?;
        let got = io::read_cloud_as(&out, self.output).map_err(|e| unreadable("cloud", &out, e))?;
        Ok(Filtered {
            cloud: got,
            source: None,
            diagnostics: timed(s),
        })
    }
}

/// The three external entries.
pub fn entries() -> Vec<MethodEntry> {
    vec![
        custom::<ExternalParams>(
            MethodKind::Reconstruct,
            "external",
            "external program",
            "any program that reads a cloud file and writes a mesh (command template)",
            DOCS,
            |p, _| Ok(Built::Reconstruct(Box::new(External::new("external", p)?))),
        ),
        custom::<ExternalParams>(
            MethodKind::Normals,
            "external-normals",
            "external program",
            "any program that reads a cloud file and writes it back with normals",
            DOCS,
            |p, _| {
                Ok(Built::Normals(Box::new(External::new(
                    "external-normals",
                    p,
                )?)))
            },
        ),
        custom::<ExternalParams>(
            MethodKind::Filter,
            "external-filter",
            "external program",
            "any program that reads a cloud file and writes a cloud",
            DOCS,
            |p, _| {
                Ok(Built::Filter(Box::new(External::new(
                    "external-filter",
                    p,
                )?)))
            },
        ),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn placeholders_are_found_and_checked() {
        assert_eq!(placeholders("a {input} {x_1} {not a} {}"), ["input", "x_1"]);
        let p = ExternalParams {
            command: "prog {input} {radius}".into(),
            ..Default::default()
        };
        assert!(matches!(
            External::new("external", p),
            Err(MethodError::InvalidParameter { .. })
        ));
    }

    #[test]
    fn values_render_as_text() {
        assert_eq!(value_text(&serde_json::json!([1, 2.5, "a"])), "1,2.5,a");
        assert_eq!(value_text(&serde_json::json!("s")), "s");
        assert_eq!(quote(Path::new("/t/it's")), r"'/t/it'\''s'");
        assert!(is_simple("python3 x.py 'a' b") && !is_simple("a; b"));
    }
}
