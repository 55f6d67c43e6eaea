//! The crates' shape, checked on every `cargo test` (docs/ARCHITECTURE.md, "How the shape is
//! kept"):
//!
//! 1. no crate has an import circle between its files,
//! 2. imports point down the layer table [`LAYERS`],
//! 3. no source file grows past [`MAX_LINES`] lines (unit tests aside).
//!
//! Imports are read the way `../shared/tools/import-circles.py` reads them, so this test and
//! the script agree on every circle; beyond the script, a `crate::` path through a module the
//! crate root re-exports under a short name (`pub use features::looks::tint;`) is resolved to
//! that module, so an upward import cannot hide behind a re-export. Std only: Cargo cannot enforce layers inside one crate, and
//! a tool like `cargo-modules` would need its own install and a rust-analyzer build on CI.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};

/// The layer table: per crate (its folder under `crates/`), its top-level modules (the first
/// path component under `src/`) with their rank. A file may import files of its own rank or
/// lower, never higher; the crate root (`lib.rs`/`main.rs`) sits above every rank. Every
/// top-level module of a listed crate must be here, so a new module is placed on purpose.
/// Crates not listed are checked for circles only.
const LAYERS: &[(&str, &[(&str, u32)])] = &[
    (
        "plume-compiler",
        &[
            // 0: leaves that know no effect: diagnostics, spans, value types, the WGSL text
            //    writer, rng.
            ("base", 0),
            // 1: the expression language of custom forces.
            ("expr", 1),
            // 2: the features an effect is made of: forces, colliders, fields, events, looks.
            ("features", 2),
            // 3: the effect IR that gathers the features' lowered forms.
            ("ir", 3),
            // 4: the stages: schema, checks, lowering, passes, integrators, WGSL kernel assembly,
            //    schedule.
            ("stages", 4),
            // 5: the f64 reference simulator, which executes the IR the stages make on their
            //    step contract (schedule, integrators, schema): no stage imports it.
            ("reference", 5),
            // 6: the accuracy pass, which runs the reference to calibrate a budget's choice;
            //    the passes reach it only through the chooser the compile driver hands them.
            ("calibration", 6),
            // 7: the single-group compile driver, and its batched form.
            ("compile", 7),
            ("batch", 7),
            // 8: effects with groups and the events between them (and their f64 reference run).
            ("graph", 8),
        ],
    ),
    (
        "plume-runtime",
        &[
            // 0: the error type every folder returns.
            ("error", 0),
            // 1: the device, a group's buffers and reading them back.
            ("device", 1),
            // 2: the GPU radix sort and the depth keys it orders.
            ("sort", 2),
            // 3: simulation: a group's steps, the event streams, `Effect`.
            ("sim", 3),
            // 4: drawing: the renderer, the raster pipelines, trails, splat, glow.
            ("draw", 4),
            // 5: headless images and exports.
            ("outputs", 5),
            // 6: what the tests and the `plume` command measure and compare against: the CPU-fed
            //    drawing and readbacks, and the benchmarks.
            ("oracle", 6),
            ("bench", 6),
        ],
    ),
    (
        "plume-cli",
        &[
            // 0: reading and compiling an effect file, with located errors; the scene depth a
            // SceneDepth collider meets where a command draws no scene; reported events' rows.
            ("load", 0),
            ("scene_depth", 0),
            ("reports", 0),
            // 1: the commands that only load and run.
            ("run", 1),
            ("render", 1),
            ("accuracy", 1),
            // 2: the commands that reuse `render`'s frame loop.
            ("bench", 2),
            ("preview", 2),
        ],
    ),
    (
        "bevy_plume",
        &[
            // 0: the main world: the asset, the component and what the plugin sets on it.
            ("asset", 0),
            ("effect", 0),
            ("bounds", 0),
            ("particle_lights", 0),
            ("mesh_particles", 0),
            ("event_reports", 0),
            ("thinning", 0),
            // The maps both worlds hold (imports nothing of the crate).
            ("shared", 0),
            // 1: the render world, which reads them; the headless runner, which waits on them.
            ("render", 1),
            ("headless", 1),
            // 2: the diagnostics, which read the render world's counts.
            ("diagnostics", 2),
            // 3: the on-screen overlay, which draws the diagnostics.
            ("overlay", 3),
        ],
    ),
];

/// The longest a source file may be, counting the lines before its unit-test module.
const MAX_LINES: usize = 600;

#[test]
fn no_import_circles() {
    let report: String = crate_sources(&workspace_root())
        .iter()
        .map(|(name, src)| circle_report(name, &ModuleGraph::load(src)))
        .collect();
    assert!(
        report.is_empty(),
        "import circles: files that reach themselves through imports.\n{report}\n\
         Break each circle by cutting one of the arrows listed: move what both sides need into \
         a module lower down, or pass it in (an argument, a trait) instead of importing it. \
         `python3 ../shared/tools/import-circles.py crates/*/src` reports the same circles."
    );
}

#[test]
fn layers_point_down() {
    let root = workspace_root();
    let mut report = String::new();
    for (name, table) in LAYERS {
        let src = root.join("crates").join(name).join("src");
        if !src.is_dir() {
            writeln!(report, "crates/{name}/src does not exist: update LAYERS").unwrap();
            continue;
        }
        for problem in layer_problems(&ModuleGraph::load(&src), table) {
            writeln!(report, "crates/{name}/src: {problem}").unwrap();
        }
    }
    assert!(
        report.is_empty(),
        "the layer rule is broken (imports must point down LAYERS in tests/layers.rs):\n\
         {report}\n\
         Move what the lower file needs down to its layer (or below), or pass it in from above \
         (an argument, a trait) instead of importing it. A module missing from the table goes \
         at the rank of the highest layer it imports, or higher."
    );
}

#[test]
fn stages_name_no_feature_variant() {
    let root = workspace_root();
    let mut report = String::new();
    for file in rust_files(&root.join("crates/plume-compiler/src/stages")) {
        let shown = file.strip_prefix(&root).unwrap_or(&file).display();
        for named in feature_variants_named(&strip_comments_and_tests(&read(&file))) {
            writeln!(report, "  {shown}: {named}").unwrap();
        }
    }
    assert!(
        report.is_empty(),
        "stages reach forces and colliders through their methods, never by variant:\n\
         {report}\nAsk the feature instead (a method on `Force`, `Term`, `ForceTerm`, `Collider` \
         or `Surface` in the feature's own module)."
    );
}

/// Each `Force::X`, `Term::X`, `Collider::X` or `Surface::X` (a variant: X capitalised) the
/// text names.
fn feature_variants_named(text: &str) -> Vec<String> {
    let mut named = Vec::new();
    for kind in ["Force::", "Term::", "Collider::", "Surface::"] {
        for (at, _) in text.match_indices(kind) {
            let before = text[..at].bytes().next_back();
            let after = text[at + kind.len()..].bytes().next();
            let whole_word = !before.is_some_and(|b| b.is_ascii_alphanumeric() || b == b'_');
            if whole_word && after.is_some_and(|b| b.is_ascii_uppercase()) {
                let end = segments_end(text.as_bytes(), at + kind.len() - 2);
                named.push(text[at..end].to_owned());
            }
        }
    }
    named
}

#[test]
fn files_stay_small() {
    let root = workspace_root();
    let mut dirs: Vec<PathBuf> = crate_sources(&root)
        .into_iter()
        .map(|(_, src)| src)
        .collect();
    dirs.push(root.join("examples"));
    let mut report = String::new();
    for file in dirs
        .iter()
        .filter(|dir| dir.is_dir())
        .flat_map(|dir| rust_files(dir))
    {
        let lines = code_lines(&read(&file));
        if lines > MAX_LINES {
            let shown = file.strip_prefix(&root).unwrap_or(&file);
            writeln!(report, "  {}: {lines} lines", shown.display()).unwrap();
        }
    }
    assert!(
        report.is_empty(),
        "files longer than {MAX_LINES} lines (not counting a trailing #[cfg(test)] module):\n\
         {report}\nSplit each into a folder of smaller modules, one concern per file."
    );
}

/// The workspace root: Cargo sets `CARGO_MANIFEST_DIR`; a bare `rustc --test` build falls back
/// to the current directory.
fn workspace_root() -> PathBuf {
    option_env!("CARGO_MANIFEST_DIR").map_or_else(
        || std::env::current_dir().expect("current directory"),
        PathBuf::from,
    )
}

/// Every `crates/<name>/src` folder as (name, path), sorted by name.
fn crate_sources(root: &Path) -> Vec<(String, PathBuf)> {
    let mut crates: Vec<_> = fs::read_dir(root.join("crates"))
        .expect("read crates/")
        .map(|entry| entry.expect("crates/ entry").path())
        .filter(|dir| dir.join("src").is_dir())
        .map(|dir| {
            (
                dir.file_name().unwrap().to_string_lossy().into_owned(),
                dir.join("src"),
            )
        })
        .collect();
    crates.sort();
    crates
}

/// Every `.rs` file under `dir`, recursively, sorted.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let mut dirs = vec![dir.to_path_buf()];
    while let Some(dir) = dirs.pop() {
        let entries = fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
        for entry in entries {
            let path = entry.expect("directory entry").path();
            if path.is_dir() {
                dirs.push(path);
            } else if path.extension().is_some_and(|ext| ext == "rs") {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}

/// A file's text; like the script, invalid UTF-8 is replaced rather than fatal.
fn read(file: &Path) -> String {
    let bytes = fs::read(file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    String::from_utf8_lossy(&bytes).into_owned()
}

/// The files of one crate's `src/` and which of them import which.
struct ModuleGraph {
    /// Each file's path under `src/`, e.g. `stages/wgsl/mod.rs`.
    files: Vec<String>,
    /// Each file's module path: `mod.rs`, `lib.rs` and `main.rs` name their folder, so the
    /// crate root is `[]`.
    modules: Vec<Vec<String>>,
    /// `imports[i]`: the files file `i` imports, sorted. Never itself or its own ancestors: a
    /// child naming its parent (`super::`) reaches for re-exports, not for a dependency.
    imports: Vec<Vec<usize>>,
}

impl ModuleGraph {
    fn load(src: &Path) -> Self {
        // One file per module path, as in the script's dict.
        let mut by_module = BTreeMap::new();
        for path in rust_files(src) {
            let relative = path.strip_prefix(src).unwrap();
            let mut module: Vec<String> = relative
                .with_extension("")
                .iter()
                .map(|part| part.to_string_lossy().into_owned())
                .collect();
            if matches!(
                module.last().map(String::as_str),
                Some("mod" | "lib" | "main")
            ) {
                module.pop();
            }
            by_module.insert(module, relative.to_string_lossy().into_owned());
        }
        let (modules, files): (Vec<_>, Vec<_>) = by_module.into_iter().unzip();
        let index: BTreeMap<&[String], usize> = modules
            .iter()
            .enumerate()
            .map(|(i, module)| (module.as_slice(), i))
            .collect();
        // The crate root's re-exports of modules under short names (`pub use features::looks::
        // tint;`): `crate::tint::...` is an import of that module wherever it is written.
        let aliases = match index.get(&[][..]) {
            Some(&root) => reexported_modules(&read(&src.join(&files[root])), &index),
            None => BTreeMap::new(),
        };
        let imports = modules
            .iter()
            .zip(&files)
            .map(|(module, file)| {
                let text = strip_comments_and_tests(&read(&src.join(file)));
                let is_child = |name: &str| {
                    index.contains_key([module.as_slice(), &[name.to_owned()]].concat().as_slice())
                };
                let targets: BTreeSet<usize> = import_paths(&text, is_child)
                    .iter()
                    .filter_map(|path| resolve(module, path, &index, &aliases))
                    .filter(|&target| !module.starts_with(&modules[target]))
                    .collect();
                targets.into_iter().collect()
            })
            .collect();
        Self {
            files,
            modules,
            imports,
        }
    }

    /// The import circles (strongly connected sets of more than one file), largest first, each
    /// in file order. Tarjan's algorithm, iterative so deep chains cannot overflow the stack.
    fn circles(&self) -> Vec<Vec<usize>> {
        const UNSEEN: usize = usize::MAX;
        let count = self.imports.len();
        let (mut order, mut low) = (vec![UNSEEN; count], vec![0; count]);
        let (mut on_stack, mut stack, mut circles) = (vec![false; count], Vec::new(), Vec::new());
        let mut next = 0;
        for start in 0..count {
            if order[start] != UNSEEN {
                continue;
            }
            // The depth-first path: (file, how many of its imports were followed).
            let mut path = vec![(start, 0)];
            (order[start], low[start], on_stack[start]) = (next, next, true);
            stack.push(start);
            next += 1;
            while let Some(&(file, followed)) = path.last() {
                if let Some(&target) = self.imports[file].get(followed) {
                    path.last_mut().unwrap().1 += 1;
                    if order[target] == UNSEEN {
                        (order[target], low[target], on_stack[target]) = (next, next, true);
                        stack.push(target);
                        next += 1;
                        path.push((target, 0));
                    } else if on_stack[target] {
                        low[file] = low[file].min(order[target]);
                    }
                    continue;
                }
                path.pop();
                if let Some(&(parent, _)) = path.last() {
                    low[parent] = low[parent].min(low[file]);
                }
                if low[file] == order[file] {
                    let at = stack.iter().rposition(|&f| f == file).unwrap();
                    let mut component = stack.split_off(at);
                    for &member in &component {
                        on_stack[member] = false;
                    }
                    if component.len() > 1 {
                        component.sort_unstable();
                        circles.push(component);
                    }
                }
            }
        }
        circles.sort_by_key(|circle| std::cmp::Reverse(circle.len()));
        circles
    }
}

/// The circles of one crate, each file with the files of its circle that it imports: the arrows
/// one of which must go. Empty when there are none.
fn circle_report(name: &str, graph: &ModuleGraph) -> String {
    let mut report = String::new();
    for circle in graph.circles() {
        writeln!(
            report,
            "crates/{name}/src: a circle of {} files:",
            circle.len()
        )
        .unwrap();
        for &file in &circle {
            let targets: Vec<&str> = graph.imports[file]
                .iter()
                .filter(|target| circle.contains(target))
                .map(|&target| graph.files[target].as_str())
                .collect();
            writeln!(
                report,
                "  {} imports {}",
                graph.files[file],
                targets.join(", ")
            )
            .unwrap();
        }
    }
    report
}

/// Breaches of the layer rule in one crate: top-level modules missing from `table`, and files
/// importing a file of a higher rank.
fn layer_problems(graph: &ModuleGraph, table: &[(&str, u32)]) -> Vec<String> {
    let top = |file: usize| {
        graph.modules[file]
            .first()
            .map_or("the crate root", String::as_str)
    };
    // None for a module missing from the table; the crate root ranks above everything.
    let ranks: Vec<Option<u32>> = (0..graph.files.len())
        .map(|file| match graph.modules[file].first() {
            None => Some(u32::MAX),
            Some(module) => table
                .iter()
                .find(|(name, _)| name == module)
                .map(|&(_, rank)| rank),
        })
        .collect();
    let mut problems = Vec::new();
    let mut missing = BTreeSet::new();
    for file in (0..graph.files.len()).filter(|&file| ranks[file].is_none()) {
        if missing.insert(top(file)) {
            problems.push(format!(
                "top-level module `{}` ({}) has no rank: add it to the layer table in \
                 tests/layers.rs",
                top(file),
                graph.files[file]
            ));
        }
    }
    for (file, targets) in graph.imports.iter().enumerate() {
        for &target in targets {
            if let (Some(rank), Some(target_rank)) = (ranks[file], ranks[target]) {
                if target_rank > rank {
                    problems.push(format!(
                        "{} (`{}`, rank {rank}) imports {} (`{}`, rank {target_rank})",
                        graph.files[file],
                        top(file),
                        graph.files[target],
                        top(target)
                    ));
                }
            }
        }
    }
    problems
}

/// The lines of `text` before its unit-test module (`#[cfg(test)] mod <name> {`), if any.
fn code_lines(text: &str) -> usize {
    let end = test_module_start(text, None).map_or(text.len(), |at| {
        text[..at].rfind('\n').map_or(0, |newline| newline + 1)
    });
    text[..end].lines().count()
}

/// Where the first `#[cfg(test)] mod <name> {` begins, whitespace allowed between the tokens
/// as in the script's regex; `None` accepts any module name.
fn test_module_start(text: &str, name: Option<&str>) -> Option<usize> {
    const ATTRIBUTE: &str = "#[cfg(test)]";
    let opens_test_module = |after: &str| {
        let Some(after_mod) = after.trim_start().strip_prefix("mod") else {
            return false;
        };
        let ident = after_mod.trim_start();
        let ident_len = ident.find(|c: char| !(c.is_alphanumeric() || c == '_'));
        let (ident, rest) = ident.split_at(ident_len.unwrap_or(ident.len()));
        ident.len() < after_mod.len() // whitespace after `mod`
            && !ident.is_empty()
            && name.is_none_or(|name| name == ident)
            && rest.trim_start().starts_with('{')
    };
    text.match_indices(ATTRIBUTE)
        .map(|(at, _)| at)
        .find(|&at| opens_test_module(&text[at + ATTRIBUTE.len()..]))
}

/// The text the script searches for imports: `//` comments, then `/* */` comments removed
/// (naively, even inside string literals, as the script does), and a trailing
/// `#[cfg(test)] mod tests {` cut off with everything after it.
fn strip_comments_and_tests(text: &str) -> String {
    let without_line_comments: Vec<&str> = text
        .split('\n')
        .map(|line| line.split_once("//").map_or(line, |(code, _)| code))
        .collect();
    let without_line_comments = without_line_comments.join("\n");
    let mut stripped = String::with_capacity(without_line_comments.len());
    let mut rest = without_line_comments.as_str();
    while let Some(open) = rest.find("/*") {
        let Some(close) = rest[open + 2..].find("*/") else {
            break;
        };
        stripped.push_str(&rest[..open]);
        rest = &rest[open + 2 + close + 2..];
    }
    stripped.push_str(rest);
    if let Some(at) = test_module_start(&stripped, Some("tests")) {
        stripped.truncate(at);
    }
    stripped
}

/// Every module path the stripped text names, collected as the script does: `crate::`,
/// `super::` and `self::` paths; grouped `use` items, one path each; and bare paths whose first
/// segment is a child module (`is_child`), taken as `self::child::...`.
fn import_paths(text: &str, is_child: impl Fn(&str) -> bool) -> Vec<String> {
    let mut paths: Vec<String> = find_all(text, qualified_path_at)
        .map(str::to_owned)
        .collect();
    for group in find_all(text, group_at) {
        let (prefix, items) = group.split_once("::{").unwrap();
        let items = items.strip_suffix('}').unwrap();
        for item in items.split(|c: char| c == ',' || c.is_whitespace()) {
            let item = item.trim_matches(|c| matches!(c, '{' | '}' | ' '));
            if item == "self" {
                paths.push(prefix.to_owned());
            } else if item.starts_with(char::is_alphabetic) {
                paths.push(format!("{prefix}::{}", item.split("::").next().unwrap()));
            }
        }
    }
    let bare =
        find_all(text, bare_path_at).filter(|path| is_child(path.split("::").next().unwrap()));
    paths.extend(bare.map(|path| format!("self::{path}")));
    paths
}

/// The modules a crate root re-exports under their last name (`pub use a::b::{c, d};`), as
/// name → module path: only paths that are modules of `index` (a re-exported type is no
/// module).
fn reexported_modules(
    root: &str,
    index: &BTreeMap<&[String], usize>,
) -> BTreeMap<String, Vec<String>> {
    let text = strip_comments_and_tests(root);
    let mut aliases = BTreeMap::new();
    for statement in text.split(';') {
        let Some(at) = statement.find("pub use ") else {
            continue;
        };
        let used: String = statement[at + "pub use ".len()..]
            .chars()
            .filter(|c| !c.is_whitespace())
            .collect();
        let used = used.strip_prefix("crate::").unwrap_or(&used);
        // `a::b::{c, d}` or `a::b::c`: each item a path below the prefix.
        let (prefix, items) = match used.split_once("::{") {
            Some((prefix, items)) => (prefix, items.trim_end_matches('}').split(',').collect()),
            None => ("", vec![used]),
        };
        for item in items.into_iter().filter(|item| !item.is_empty()) {
            let (path, alias) = item.split_once("as").unwrap_or((item, ""));
            let full: Vec<String> = prefix
                .split("::")
                .chain(path.split("::"))
                .filter(|part| !part.is_empty())
                .map(str::to_owned)
                .collect();
            let name = if alias.is_empty() {
                full.last()
            } else {
                Some(&alias.to_owned())
            };
            if let (true, Some(name)) =
                (full.len() > 1 && index.contains_key(full.as_slice()), name)
            {
                aliases.insert(name.clone(), full.clone());
            }
        }
    }
    aliases
}

/// The module that `path`, named in `module`, lands in: the longest existing prefix, a
/// `crate::` path through the crate root's re-exports (`aliases`) resolved to the module.
fn resolve(
    module: &[String],
    path: &str,
    index: &BTreeMap<&[String], usize>,
    aliases: &BTreeMap<String, Vec<String>>,
) -> Option<usize> {
    let mut parts = path.split("::").peekable();
    let mut full = Vec::new();
    if parts.next_if_eq(&"crate").is_none() {
        full.extend_from_slice(module);
        while let Some(step) = parts.next_if(|part| matches!(*part, "super" | "self")) {
            if step == "super" {
                full.pop();
            }
        }
    } else if let Some(target) = parts
        .peek()
        .filter(|first| !index.contains_key(&[first.to_string()][..]))
        .and_then(|first| aliases.get(*first))
    {
        parts.next();
        full.extend_from_slice(target);
    }
    full.extend(parts.map(str::to_owned));
    (0..=full.len())
        .rev()
        .find_map(|len| index.get(&full[..len]).copied())
}

/// The non-overlapping matches in `text`, left to right, of a pattern given as the end of its
/// match starting at a position (the script's regexes, hand-written).
fn find_all(text: &str, match_at: fn(&str, usize) -> Option<usize>) -> impl Iterator<Item = &str> {
    let mut at = 0;
    std::iter::from_fn(move || {
        while at < text.len() {
            if let Some(end) = match_at(text, at) {
                let found = &text[at..end];
                at = end;
                return Some(found);
            }
            at += 1;
        }
        None
    })
}

/// Regex `\w` for the character before `at`.
fn word_before(text: &str, at: usize) -> bool {
    text[..at]
        .chars()
        .next_back()
        .is_some_and(|c| c.is_alphanumeric() || c == '_')
}

fn is_ident_start(byte: u8) -> bool {
    byte.is_ascii_alphabetic() || byte == b'_'
}

/// `\b(crate|super|self)` at `at`: the keyword's end.
fn keyword_at(text: &str, at: usize) -> Option<usize> {
    let keyword = ["crate", "super", "self"]
        .into_iter()
        .find(|keyword| text.as_bytes()[at..].starts_with(keyword.as_bytes()))?;
    (!word_before(text, at)).then_some(at + keyword.len())
}

/// The end of the `(::ident)*` run from `at`.
fn segments_end(bytes: &[u8], mut at: usize) -> usize {
    while bytes[at..].starts_with(b"::") && bytes.get(at + 2).copied().is_some_and(is_ident_start) {
        at += 3;
        while bytes
            .get(at)
            .is_some_and(|&b| b.is_ascii_alphanumeric() || b == b'_')
        {
            at += 1;
        }
    }
    at
}

/// The script's `PATH`: `\b(crate|super|self)(::ident)+`.
fn qualified_path_at(text: &str, at: usize) -> Option<usize> {
    let keyword_end = keyword_at(text, at)?;
    let end = segments_end(text.as_bytes(), keyword_end);
    (end > keyword_end).then_some(end)
}

/// The script's `GROUP`: `\b(crate|super|self)(::ident)*::{...}`, the braces holding no `;`.
fn group_at(text: &str, at: usize) -> Option<usize> {
    let bytes = text.as_bytes();
    let prefix_end = segments_end(bytes, keyword_at(text, at)?);
    if !bytes[prefix_end..].starts_with(b"::{") {
        return None;
    }
    let open = prefix_end + 3;
    let close = open + bytes[open..].iter().position(|&b| b == b'}' || b == b';')?;
    (bytes[close] == b'}').then_some(close + 1)
}

/// The script's `BARE`: `(?<![:\w])[a-z_][a-z0-9_]*(::ident)+`.
fn bare_path_at(text: &str, at: usize) -> Option<usize> {
    let bytes = text.as_bytes();
    let lower = |b: &u8| b.is_ascii_lowercase() || *b == b'_';
    if !lower(&bytes[at]) || (at > 0 && bytes[at - 1] == b':') || word_before(text, at) {
        return None;
    }
    let mut first_end = at + 1;
    while bytes
        .get(first_end)
        .is_some_and(|b| lower(b) || b.is_ascii_digit())
    {
        first_end += 1;
    }
    let end = segments_end(bytes, first_end);
    (end > first_end).then_some(end)
}

// The checker's own tests, on small source trees: they make sure each rule can fail.

/// A throwaway `src/` folder under the system temp folder, removed on drop.
struct TempTree(PathBuf);

impl TempTree {
    fn new(test: &str, files: &[(&str, &str)]) -> Self {
        let dir = std::env::temp_dir().join(format!("plume-layers-{test}-{}", std::process::id()));
        // A leftover from an interrupted run must not leak into this one.
        let _ = fs::remove_dir_all(&dir);
        for (path, text) in files {
            let path = dir.join(path);
            fs::create_dir_all(path.parent().unwrap()).unwrap();
            fs::write(path, text).unwrap();
        }
        Self(dir)
    }

    fn graph(&self) -> ModuleGraph {
        ModuleGraph::load(&self.0)
    }
}

impl Drop for TempTree {
    fn drop(&mut self) {
        let _ = fs::remove_dir_all(&self.0);
    }
}

impl ModuleGraph {
    /// The files that `file` imports, by path under `src/`.
    fn imports_of(&self, file: &str) -> Vec<&str> {
        let at = self
            .files
            .iter()
            .position(|f| f == file)
            .expect("file in the tree");
        self.imports[at]
            .iter()
            .map(|&target| self.files[target].as_str())
            .collect()
    }
}

#[test]
fn a_circle_is_found_with_its_arrows() {
    let tree = TempTree::new(
        "circle",
        &[
            ("lib.rs", "mod a;\nmod b;\nmod c;\nmod d;\n"),
            ("a.rs", "use crate::b::B;\npub struct A;\n"),
            ("b.rs", "use crate::a::A;\npub struct B;\n"),
            ("c.rs", "pub struct C;\n"),
            ("d.rs", "use crate::a::A;\n"), // into the circle, not part of it
        ],
    );
    let graph = tree.graph();
    let circles: Vec<Vec<&str>> = graph
        .circles()
        .iter()
        .map(|circle| {
            circle
                .iter()
                .map(|&file| graph.files[file].as_str())
                .collect()
        })
        .collect();
    assert_eq!(circles, [["a.rs", "b.rs"]]);
    let report = circle_report("demo", &graph);
    assert!(
        report.contains("a.rs imports b.rs") && report.contains("b.rs imports a.rs"),
        "{report}"
    );
}

#[test]
fn a_child_using_super_is_not_a_circle() {
    let tree = TempTree::new(
        "super",
        &[
            ("lib.rs", "mod parent;\n"),
            (
                "parent/mod.rs",
                "mod child;\npub use child::Thing;\npub struct Parent;\n",
            ),
            (
                "parent/child.rs",
                "use super::Parent;\npub struct Thing(Parent);\n",
            ),
        ],
    );
    let graph = tree.graph();
    assert_eq!(graph.imports_of("parent/mod.rs"), ["parent/child.rs"]);
    assert!(graph.imports_of("parent/child.rs").is_empty());
    assert!(graph.circles().is_empty());
}

#[test]
fn a_grouped_use_is_expanded() {
    let tree = TempTree::new(
        "grouped",
        &[
            ("lib.rs", "mod a;\nmod b;\nmod c;\n"),
            ("a.rs", "use crate::{b, c::C};\n"),
            ("b.rs", ""),
            ("c.rs", "pub struct C;\n"),
        ],
    );
    assert_eq!(tree.graph().imports_of("a.rs"), ["b.rs", "c.rs"]);
}

#[test]
fn comments_and_unit_tests_are_ignored() {
    let tree = TempTree::new(
        "comments",
        &[
            ("lib.rs", "mod a;\nmod b;\nmod c;\n"),
            (
                "a.rs",
                "// see crate::b::f\n/* and crate::c */\n\
                 #[cfg(test)]\nmod tests {\n    use crate::b;\n}\n",
            ),
            ("b.rs", "pub fn f() {}\n"),
            ("c.rs", ""),
        ],
    );
    assert!(tree.graph().imports_of("a.rs").is_empty());
}

#[test]
fn an_upward_import_and_an_unranked_module_are_reported() {
    let tree = TempTree::new(
        "upward",
        &[
            ("lib.rs", "mod high;\nmod low;\nmod new;\n"),
            ("low/mod.rs", "use crate::high::H;\n"),
            ("high.rs", "use crate::low;\npub struct H;\n"), // downward: fine
            ("new.rs", ""),
        ],
    );
    let problems = layer_problems(&tree.graph(), &[("low", 0), ("high", 1)]);
    assert_eq!(problems.len(), 2, "{problems:#?}");
    assert!(
        problems[0].contains("`new` (new.rs) has no rank"),
        "{problems:#?}"
    );
    assert_eq!(
        problems[1],
        "low/mod.rs (`low`, rank 0) imports high.rs (`high`, rank 1)"
    );
}

#[test]
fn an_upward_import_through_a_root_reexport_is_reported() {
    // `crate::tint` is `high::looks::tint`, re-exported by the root under its short name.
    let tree = TempTree::new(
        "reexport",
        &[
            (
                "lib.rs",
                "mod high;\nmod low;\npub use high::looks::{tint, glow as shine};\n",
            ),
            (
                "low/mod.rs",
                "fn f() { crate::shine::g(); }\nuse crate::tint::T;\n",
            ),
            ("high/mod.rs", "pub mod looks;\n"),
            ("high/looks/mod.rs", "pub mod tint;\npub mod glow;\n"),
            ("high/looks/tint.rs", "pub struct T;\n"),
            ("high/looks/glow.rs", "pub fn g() {}\n"),
        ],
    );
    let problems = layer_problems(&tree.graph(), &[("low", 0), ("high", 1)]);
    assert_eq!(
        problems,
        [
            "low/mod.rs (`low`, rank 0) imports high/looks/glow.rs (`high`, rank 1)",
            "low/mod.rs (`low`, rank 0) imports high/looks/tint.rs (`high`, rank 1)"
        ],
        "{problems:#?}"
    );
}

#[test]
fn a_feature_variant_named_in_code_is_found() {
    let text = "match t { Term::Custom(c) => 1, _ => 0 }\nlet f = forces::Force::Wind;\n\
                let g = MyTerm::Other; t.as_dyn().linear(); Term::as_dyn(t);";
    assert_eq!(
        feature_variants_named(text),
        ["Force::Wind", "Term::Custom"]
    );
    let commented = "// Term::Custom\nfn f() {}";
    assert!(feature_variants_named(&strip_comments_and_tests(commented)).is_empty());
}

#[test]
fn unit_tests_do_not_count_towards_the_size() {
    let text = "fn a() {}\nfn b() {}\n\n#[cfg(test)]\nmod tests {\n    fn c() {}\n}\n";
    assert_eq!(code_lines(text), 3);
    assert_eq!(code_lines("fn a() {}\n"), 1);
}
