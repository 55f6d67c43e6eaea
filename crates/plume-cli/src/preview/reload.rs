//! Hot reload: the effect file is watched, recompiled when it changes, and the outcome decides
//! what the preview runs. A valid new effect replaces the old one (restarted from t = 0); an
//! invalid one leaves the last good effect running and reports its diagnostics, rustc-style
//! with file:line:col and a caret; a file that cannot be read (deleted, renamed away) is
//! reported and the last good effect keeps running.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{channel, Receiver};
use std::time::{Duration, Instant};

use notify_debouncer_mini::notify::{RecommendedWatcher, RecursiveMode};
use notify_debouncer_mini::{new_debouncer, DebounceEventResult, Debouncer};
use plume_compiler::graph::{compile_graph_str, CompiledGraph};
use plume_compiler::CompileOptions;

/// How long a burst of file events must settle before the file is read (editors write, rename
/// and touch in quick succession).
pub const DEBOUNCE: Duration = Duration::from_millis(100);

/// What a reload found.
#[derive(Debug)]
pub enum Outcome {
    /// The file compiled: this effect (its groups) now runs, from t = 0. Its warnings come
    /// rendered.
    Replaced(Box<CompiledGraph>, String),
    /// The file has errors, rendered rustc-style; the last good effect keeps running.
    Invalid(String),
    /// The file could not be read; the last good effect keeps running.
    Unreadable(String),
    /// The file's text is what was last compiled (an editor touched it): nothing to do.
    Unchanged,
}

/// The effect file and the last effect that compiled from it.
pub struct EffectFile {
    path: PathBuf,
    options: CompileOptions,
    last_text: Option<String>,
    good: Option<CompiledGraph>,
}

impl EffectFile {
    /// The file at `path`, compiled with `options` (the command line's overrides).
    pub fn new(path: &Path, options: CompileOptions) -> Self {
        Self {
            path: path.to_path_buf(),
            options: crate::load::options_for(path, &options),
            last_text: None,
            good: None,
        }
    }

    /// The file's name as diagnostics show it.
    pub fn name(&self) -> String {
        self.path.display().to_string()
    }

    /// Reads and compiles the file. A valid effect becomes the good one.
    pub fn reload(&mut self) -> Outcome {
        let text = match std::fs::read_to_string(&self.path) {
            Ok(t) => t,
            Err(e) => {
                self.last_text = None;
                return Outcome::Unreadable(format!(
                    "{}: error: cannot read the effect file: {e}",
                    self.name()
                ));
            }
        };
        if self.last_text.as_deref() == Some(text.as_str()) {
            return Outcome::Unchanged;
        }
        self.last_text = Some(text.clone());
        match compile_graph_str(&text, &self.options) {
            Ok(compiled) => {
                let found = compiled.all_warnings();
                let warnings = match found.is_empty() {
                    true => String::new(),
                    false => found.render(&self.name(), &text),
                };
                self.good = Some(compiled.clone());
                Outcome::Replaced(Box::new(compiled), warnings)
            }
            Err(e) => Outcome::Invalid(e.render(&self.name(), &text)),
        }
    }

    /// When the file was last written (its modification time), for the time from save to
    /// new frame.
    pub fn saved_at(&self) -> Option<std::time::SystemTime> {
        std::fs::metadata(&self.path)
            .and_then(|m| m.modified())
            .ok()
    }

    /// The last effect that compiled, if any did.
    pub fn good(&self) -> Option<&CompiledGraph> {
        self.good.as_ref()
    }
}

/// Watches the effect file's directory (editors often save by renaming a new file over the
/// old one, which a watch on the file itself would lose) and reports changes to the file.
pub struct Watcher {
    _debouncer: Debouncer<RecommendedWatcher>,
    events: Receiver<DebounceEventResult>,
    file: OsString,
}

impl Watcher {
    /// Starts watching `path`.
    pub fn new(path: &Path) -> Result<Self, String> {
        let file = path
            .file_name()
            .ok_or_else(|| format!("{}: not a file", path.display()))?
            .to_os_string();
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let (tx, events) = channel();
        let mut debouncer = new_debouncer(DEBOUNCE, tx)
            .map_err(|e| format!("cannot watch {}: {e}", dir.display()))?;
        debouncer
            .watcher()
            .watch(&dir, RecursiveMode::NonRecursive)
            .map_err(|e| format!("cannot watch {}: {e}", dir.display()))?;
        Ok(Self {
            _debouncer: debouncer,
            events,
            file,
        })
    }

    /// Whether the file changed since the last call (never waits). Returns when the change
    /// was noticed.
    pub fn changed(&self) -> Option<Instant> {
        let mut seen = None;
        while let Ok(result) = self.events.try_recv() {
            if let Ok(events) = result {
                if events
                    .iter()
                    .any(|e| e.path.file_name() == Some(self.file.as_os_str()))
                {
                    seen.get_or_insert_with(Instant::now);
                }
            }
        }
        seen
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const VALID: &str = r#"Effect(
    name: "drop",
    capacity: 100,
    emitters: [Emitter(burst: 10, shape: Point((0.0, 1.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
)"#;

    fn temp_file(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("plume-reload-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir.join("effect.ron")
    }

    #[test]
    fn a_valid_change_replaces_an_invalid_one_keeps_the_last_good_a_deleted_file_is_reported() {
        let path = temp_file("logic");
        std::fs::write(&path, VALID).unwrap();
        let mut file = EffectFile::new(&path, CompileOptions::default());
        assert!(matches!(file.reload(), Outcome::Replaced(..)));
        assert_eq!(file.good().unwrap().groups[0].effect.ir.capacity, 100);

        // A touch without a change does nothing.
        assert!(matches!(file.reload(), Outcome::Unchanged));

        // A valid change replaces the effect.
        std::fs::write(&path, VALID.replace("capacity: 100", "capacity: 200")).unwrap();
        assert!(matches!(file.reload(), Outcome::Replaced(..)));
        assert_eq!(file.good().unwrap().groups[0].effect.ir.capacity, 200);

        // An invalid one keeps the last good effect and reports where the error is.
        std::fs::write(&path, VALID.replace("capacity: 100", "capacity: -5")).unwrap();
        match file.reload() {
            Outcome::Invalid(d) => {
                assert!(d.contains("effect.ron:3:"), "located: {d}");
                assert!(d.contains('^'), "with a caret: {d}");
            }
            other => panic!("expected errors, got {other:?}"),
        }
        assert_eq!(file.good().unwrap().groups[0].effect.ir.capacity, 200);

        // A syntax error too, at its line and column.
        std::fs::write(&path, "Effect(name: \"x\" capacity: 1)").unwrap();
        match file.reload() {
            Outcome::Invalid(d) => assert!(d.contains("effect.ron:1:"), "{d}"),
            other => panic!("expected a syntax error, got {other:?}"),
        }

        // A deleted file is reported; the last good effect stays.
        std::fs::remove_file(&path).unwrap();
        match file.reload() {
            Outcome::Unreadable(m) => assert!(m.contains("cannot read"), "{m}"),
            other => panic!("expected a read error, got {other:?}"),
        }
        assert_eq!(file.good().unwrap().groups[0].effect.ir.capacity, 200);

        // Written back, it compiles again.
        std::fs::write(&path, VALID).unwrap();
        assert!(matches!(file.reload(), Outcome::Replaced(..)));
        std::fs::remove_dir_all(path.parent().unwrap()).ok();
    }

    #[test]
    fn the_watcher_sees_a_save_including_one_by_rename() {
        let path = temp_file("watch");
        std::fs::write(&path, VALID).unwrap();
        let watcher = Watcher::new(&path).unwrap();
        let wait = |what: &str| {
            let start = Instant::now();
            while start.elapsed() < Duration::from_secs(10) {
                if watcher.changed().is_some() {
                    return;
                }
                std::thread::sleep(Duration::from_millis(20));
            }
            panic!("no change seen after {what}");
        };
        std::fs::write(&path, VALID.replace("100", "101")).unwrap();
        wait("a write");
        // The way many editors save: a new file renamed over the old one.
        let tmp = path.with_extension("ron.tmp");
        std::fs::write(&tmp, VALID.replace("100", "102")).unwrap();
        std::fs::rename(&tmp, &path).unwrap();
        wait("a rename");
        // Another file in the directory is not this one.
        std::thread::sleep(DEBOUNCE * 3);
        while watcher.changed().is_some() {}
        std::fs::write(path.with_file_name("other.ron"), "x").unwrap();
        std::thread::sleep(DEBOUNCE * 5);
        assert!(
            watcher.changed().is_none(),
            "another file's change was reported"
        );
        std::fs::remove_dir_all(path.parent().unwrap()).ok();
    }
}
