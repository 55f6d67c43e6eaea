//! Calibrations remembered on disk (when a host asks: [`remember_calibrations_in`]), so that a
//! budgeted file compiled again in another process (`plume check` run twice, a game started
//! again) takes its choice back instead of calibrating again, most of a first compile's time
//! (docs/performance.md, "The compiler's own speed"). Each choice is a small RON file named by the
//! effect's content key (its lowered IR, seed aside, and whether the closed form applies: the
//! accuracy pass's in-memory key), in a folder named by the compiler's build (a hash of its
//! sources), so no build reuses another's choices; folders of other builds are removed when a new
//! one is made. A file that cannot be read or parsed is no error: the effect is calibrated again
//! and the file rewritten. Files are written aside and renamed, so a reader never sees half of one.

use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock};

use serde::{Deserialize, Serialize};

use crate::base::diagnostics::Diagnostic;
use crate::base::values::Integrator;
use crate::features::accuracy::Choice;

/// The compiler's build, from its sources' hash (build.rs).
const BUILD: &str = env!("PLUME_COMPILER_BUILD");

/// What a calibration decided, as stored: the accuracy budget's choice and the integrator the
/// pass set, with the warning it gave (its path, message and lookup path).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct Stored {
    pub(crate) choice: Option<Choice>,
    pub(crate) half_motion: bool,
    pub(crate) half_estimate: Option<f64>,
    pub(crate) integrator: Integrator,
    pub(crate) substeps: u32,
    pub(crate) integrator_reason: String,
    pub(crate) warning: Option<(String, String, String)>,
}

impl Stored {
    /// The warning as the pass returns it: a diagnostic and its lookup path.
    pub(crate) fn warning(&self) -> Option<(Diagnostic, String)> {
        self.warning
            .as_ref()
            .map(|(path, message, lookup)| (Diagnostic::warning(path, message), lookup.clone()))
    }
}

fn folder() -> &'static Mutex<Option<PathBuf>> {
    static FOLDER: OnceLock<Mutex<Option<PathBuf>>> = OnceLock::new();
    FOLDER.get_or_init(Default::default)
}

/// Remembers calibrations in `dir` (made when first written to) from now on, in this process;
/// None stops. `plume` uses `$PLUME_CACHE_DIR`, else `$XDG_CACHE_HOME/plume`, else
/// `~/.cache/plume`. Compiling reads and writes there only for files with an `accuracy`
/// budget.
///
/// ```
/// use plume_compiler::calibration::cache::remember_calibrations_in;
/// let dir = std::env::temp_dir().join(format!("plume-doc-cache-{}", std::process::id()));
/// remember_calibrations_in(Some(dir.clone()));
/// let src = r#"Effect(name: "pulled", capacity: 64,
///     emitters: [Emitter(burst: 64, shape: Sphere(center: (0.0, 0.0, 0.0), radius: 1.0),
///                        velocity: Radial(speed: (0.5, 1.0)))],
///     forces: [Attractor(center: (0.0, 0.0, 0.0), strength: 2.0, range: 5.0)],
///     accuracy: (position: 0.05, over: 1.0))"#;
/// plume_compiler::compile_str(src, &Default::default()).unwrap();
/// // One choice stored, under this build's folder.
/// let builds: Vec<_> = std::fs::read_dir(dir.join("calibrations")).unwrap().collect();
/// assert_eq!(builds.len(), 1);
/// remember_calibrations_in(None);
/// ```
pub fn remember_calibrations_in(dir: Option<PathBuf>) {
    if let Ok(mut f) = folder().lock() {
        *f = dir;
    }
}

/// This build's folder under the one set, if any.
fn build_folder() -> Option<PathBuf> {
    let root = folder().lock().ok()?.clone()?;
    Some(root.join("calibrations").join(BUILD))
}

fn file(dir: &Path, key: u64) -> PathBuf {
    dir.join(format!("{key:016x}.ron"))
}

/// The choice stored for `key` by this build, if any and readable.
pub(crate) fn load(key: u64) -> Option<Stored> {
    let dir = build_folder()?;
    let text = std::fs::read_to_string(file(&dir, key)).ok()?;
    ron::from_str(&text).ok()
}

/// Stores `stored` for `key`; failures (a read-only disk, a full one) are ignored: the cache
/// only saves time.
pub(crate) fn store(key: u64, stored: &Stored) {
    let Some(dir) = build_folder() else {
        return;
    };
    if !dir.is_dir() {
        if std::fs::create_dir_all(&dir).is_err() {
            return;
        }
        // Another build's choices are never read again.
        if let Some(Ok(builds)) = dir.parent().map(std::fs::read_dir) {
            for other in builds.flatten() {
                if other.path() != dir {
                    let _ = std::fs::remove_dir_all(other.path());
                }
            }
        }
    }
    let Ok(text) = ron::to_string(stored) else {
        return;
    };
    let target = file(&dir, key);
    let aside = target.with_extension(format!(
        "ron.{}.{:?}",
        std::process::id(),
        std::thread::current().id()
    ));
    if std::fs::write(&aside, text).is_ok() && std::fs::rename(&aside, &target).is_err() {
        let _ = std::fs::remove_file(&aside);
    }
}
