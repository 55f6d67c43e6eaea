//! Calibrations remembered between runs of `plume` (`$PLUME_CACHE_DIR`): a budgeted file
//! compiled a second time takes its choice back from disk with the same result, a damaged
//! cache file is calibrated again and rewritten, and an empty `PLUME_CACHE_DIR` keeps
//! nothing.

use std::path::{Path, PathBuf};
use std::process::Command;

/// `plume compile effects/snow.ron --emit ir` with `env`: its success and its notes.
fn compile_snow(env: &[(&str, &Path)]) -> (bool, String) {
    let effect = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../effects/snow.ron");
    let mut command = Command::new(env!("CARGO_BIN_EXE_plume"));
    command.arg("compile").arg(effect).args(["--emit", "ir"]);
    for (name, value) in env {
        command.env(name, value);
    }
    let out = command.output().expect("plume runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The accuracy note, with the words that say it was remembered taken out.
fn accuracy_note(notes: &str) -> String {
    let line = notes
        .lines()
        .find(|l| l.contains("note: accuracy:"))
        .unwrap_or_else(|| panic!("no accuracy note in {notes}"));
    line.replace(
        " (remembered from an earlier compile of the same content)",
        "",
    )
}

/// Every file under `dir`.
fn files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for entry in std::fs::read_dir(&d).into_iter().flatten().flatten() {
            match entry.path().is_dir() {
                true => todo.push(entry.path()),
                false => out.push(entry.path()),
            }
        }
    }
    out
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("plume-cache-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn a_second_compile_takes_the_calibration_back_from_disk() {
    let cache = scratch("again");
    let env = [("PLUME_CACHE_DIR", cache.as_path())];
    let (ok, first) = compile_snow(&env);
    assert!(ok, "{first}");
    assert!(!first.contains("remembered"), "{first}");
    let stored = files(&cache);
    assert_eq!(stored.len(), 1, "one choice stored: {stored:?}");
    let (ok, second) = compile_snow(&env);
    assert!(ok, "{second}");
    assert!(
        second.contains("(remembered from an earlier compile"),
        "{second}"
    );
    assert_eq!(accuracy_note(&first), accuracy_note(&second));
    // The integrator note and the IR follow from the choice: the same both times.
    let ir_of = |notes: &str| {
        notes
            .lines()
            .filter(|l| !l.contains("note: accuracy:"))
            .collect::<Vec<_>>()
            .join("\n")
    };
    assert_eq!(ir_of(&first), ir_of(&second));
}

#[test]
fn a_damaged_cache_file_is_calibrated_again_and_rewritten() {
    let cache = scratch("damaged");
    let env = [("PLUME_CACHE_DIR", cache.as_path())];
    let (ok, first) = compile_snow(&env);
    assert!(ok, "{first}");
    let stored = files(&cache);
    let good = std::fs::read_to_string(&stored[0]).unwrap();
    std::fs::write(&stored[0], "Stored(choice: Some(Exa").unwrap();
    let (ok, again) = compile_snow(&env);
    assert!(ok, "{again}");
    assert!(!again.contains("remembered"), "{again}");
    // Calibrated again: the same choice, in its own time.
    let choice = |note: String| note.split("; calibrated on").next().unwrap().to_string();
    assert_eq!(choice(accuracy_note(&first)), choice(accuracy_note(&again)));
    let rewritten = std::fs::read_to_string(&stored[0]).unwrap();
    assert_eq!(
        rewritten.replace(char::is_numeric, ""),
        good.replace(char::is_numeric, ""),
        "the file holds the choice again (its timing aside)"
    );
}

#[test]
fn an_empty_plume_cache_dir_keeps_nothing() {
    let home = scratch("home");
    std::fs::create_dir_all(&home).unwrap();
    let empty = Path::new("");
    let env = [
        ("PLUME_CACHE_DIR", empty),
        ("HOME", home.as_path()),
        ("XDG_CACHE_HOME", home.as_path()),
    ];
    let (ok, first) = compile_snow(&env);
    assert!(ok, "{first}");
    let (ok, second) = compile_snow(&env);
    assert!(ok, "{second}");
    assert!(!second.contains("remembered"), "{second}");
    assert!(files(&home).is_empty(), "{:?}", files(&home));
}
