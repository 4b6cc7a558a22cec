//! The vendored real data sets (`datasets/real/`): their manifest
//! (`datasets/real/datasets.toml`, one `[[dataset]]` table per set with its file,
//! provenance, licence, the seed tables that use it and its measured topology) and how to
//! find it.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::{Result, SynthError};

/// File name of the manifest inside the data set directory.
pub const MANIFEST: &str = "datasets.toml";

/// Environment variable naming the data set directory (the one holding [`MANIFEST`]),
/// for installs outside a checkout.
pub const DATASETS_ENV: &str = "RECONBENCH_DATASETS";

/// What a vendored file holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RealKind {
    /// A triangle mesh (ground truth available).
    Mesh,
    /// A point cloud (no ground truth).
    Cloud,
}

/// One `[[dataset]]` of the manifest.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RealSet {
    /// Name used in experiments (`real = "fandisk"`).
    pub name: String,
    /// File name, relative to the manifest's directory.
    pub file: String,
    /// Mesh or cloud.
    pub kind: RealKind,
    /// GitHub repository the file was taken from.
    pub source_repository: String,
    /// Commit of that repository.
    pub source_commit: String,
    /// Path inside that repository.
    pub source_path: String,
    /// Licence as stated by the source.
    pub licence: String,
    /// Seed tables that use the set.
    #[serde(default)]
    pub seed_tables: Vec<String>,
    /// Vertex (or point) count.
    pub vertices: u64,
    /// Face count (0 for a cloud).
    pub faces: u64,
    /// Genus (0 for a cloud).
    pub genus: u32,
    /// Connected components (0 for a cloud).
    pub components: u32,
    /// Boundary loops (0 for a cloud).
    pub boundary_loops: u32,
    /// Whether the mesh is watertight.
    pub closed: bool,
    /// Whether the seed reconstructs the object as a closed surface (the default
    /// closedness of its ground truth).
    pub thesis_closed: bool,
    /// Free text: identity with the seed's data, substitutions.
    #[serde(default)]
    pub notes: String,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ManifestFile {
    dataset: Vec<RealSet>,
}

/// A loaded manifest.
#[derive(Debug, Clone, PartialEq)]
pub struct Manifest {
    /// Directory of the manifest (the files are relative to it).
    pub dir: PathBuf,
    /// The sets, in file order.
    pub sets: Vec<RealSet>,
}

impl Manifest {
    /// Reads `dir/datasets.toml`. Errors name the file; names must be unique.
    pub fn load(dir: &Path) -> Result<Self> {
        let path = dir.join(MANIFEST);
        let text = std::fs::read_to_string(&path).map_err(|e| {
            SynthError::Unsatisfiable(format!("cannot read {}: {e}", path.display()))
        })?;
        let file: ManifestFile = toml::from_str(&text)
            .map_err(|e| SynthError::Unsatisfiable(format!("{}: {e}", path.display())))?;
        for (i, s) in file.dataset.iter().enumerate() {
            if file.dataset[..i].iter().any(|t| t.name == s.name) {
                return Err(SynthError::Unsatisfiable(format!(
                    "{}: data set name '{}' appears twice",
                    path.display(),
                    s.name
                )));
            }
        }
        Ok(Self {
            dir: dir.to_path_buf(),
            sets: file.dataset,
        })
    }

    /// Finds the manifest: `$RECONBENCH_DATASETS` if set, else `datasets/real/` in
    /// `start` or one of its ancestors, else the checkout this binary was built from.
    pub fn locate(start: Option<&Path>) -> Result<Self> {
        if let Some(dir) = std::env::var_os(DATASETS_ENV) {
            return Self::load(Path::new(&dir));
        }
        let mut tried = Vec::new();
        let cwd = std::env::current_dir().ok();
        let start = start.map(Path::to_path_buf).or(cwd);
        if let Some(start) = start {
            for d in start.ancestors() {
                let cand = d.join("datasets").join("real");
                if cand.join(MANIFEST).is_file() {
                    return Self::load(&cand);
                }
            }
            tried.push(format!("datasets/real/ above {}", start.display()));
        }
        let built = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../datasets/real");
        if built.join(MANIFEST).is_file() {
            return Self::load(&built);
        }
        tried.push(built.display().to_string());
        Err(SynthError::Unsatisfiable(format!(
            "no real data set manifest found (tried {}); set {DATASETS_ENV} to the directory holding {MANIFEST}",
            tried.join(", ")
        )))
    }

    /// The set named `name`; the error lists the names there are.
    pub fn find(&self, name: &str) -> Result<&RealSet> {
        self.sets
            .iter()
            .find(|s| s.name == name)
            .ok_or_else(|| SynthError::UnknownName {
                what: "real data set",
                name: name.to_string(),
                valid: self
                    .sets
                    .iter()
                    .map(|s| s.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            })
    }

    /// Path of a set's file.
    pub fn path_of(&self, set: &RealSet) -> PathBuf {
        self.dir.join(&set.file)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, text: &str) {
        std::fs::write(dir.join(MANIFEST), text).unwrap();
    }

    const ONE: &str = r#"
[[dataset]]
name = "a"
file = "a.ply"
kind = "mesh"
source_repository = "o/r"
source_commit = "abc"
source_path = "a.obj"
licence = "MIT"
vertices = 4
faces = 4
genus = 0
components = 1
boundary_loops = 0
closed = true
thesis_closed = true
"#;

    #[test]
    fn loads_finds_and_names_what_is_missing() {
        let d = tempfile::tempdir().unwrap();
        write(d.path(), ONE);
        let m = Manifest::load(d.path()).unwrap();
        assert_eq!(m.sets.len(), 1);
        assert_eq!(m.find("a").unwrap().kind, RealKind::Mesh);
        assert_eq!(m.path_of(&m.sets[0]), d.path().join("a.ply"));
        let e = m.find("b").unwrap_err().to_string();
        assert!(e.contains("'b'") && e.contains("valid: a"), "{e}");
    }

    #[test]
    fn duplicate_names_and_unknown_keys_are_errors() {
        let d = tempfile::tempdir().unwrap();
        write(d.path(), &format!("{ONE}{ONE}"));
        let e = Manifest::load(d.path()).unwrap_err().to_string();
        assert!(e.contains("appears twice"), "{e}");
        write(d.path(), &ONE.replace("licence", "license"));
        let e = Manifest::load(d.path()).unwrap_err().to_string();
        assert!(e.contains("datasets.toml"), "{e}");
    }

    #[test]
    fn locate_walks_up_to_a_datasets_directory() {
        let d = tempfile::tempdir().unwrap();
        let real = d.path().join("datasets/real");
        std::fs::create_dir_all(&real).unwrap();
        write(&real, ONE);
        let deep = d.path().join("experiments/paper");
        std::fs::create_dir_all(&deep).unwrap();
        if std::env::var_os(DATASETS_ENV).is_none() {
            let m = Manifest::locate(Some(&deep)).unwrap();
            assert_eq!(m.dir, real);
        }
    }
}
