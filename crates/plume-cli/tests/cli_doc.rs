//! docs/cli.md is true to `plume --help`: the commands and what each does, and for every
//! command its usage line, each argument and option with its meaning and default, and the
//! values an option takes, as the binary's own `--help` prints them. A change to the command
//! line that the page does not follow fails here.

use std::collections::BTreeMap;
use std::process::Command;

/// One argument or option as `--help` prints it.
#[derive(Debug, Default)]
struct HelpEntry {
    /// Its first paragraph, lines joined by spaces.
    meaning: String,
    /// `[default: X]`'s X.
    default: Option<String>,
    /// `Possible values:` lines, `name: meaning`.
    values: Vec<String>,
}

/// One command's `--help`: its usage line and its entries by name (`--frames <FRAMES>`).
struct Help {
    usage: String,
    entries: BTreeMap<String, HelpEntry>,
}

fn help_text(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_plume"))
        .args(args)
        .args((args.first() != Some(&"help")).then_some("--help"))
        .output()
        .expect("plume runs");
    assert!(out.status.success(), "plume {args:?} --help failed");
    String::from_utf8(out.stdout).expect("help is UTF-8")
}

/// Parses clap's long help: entry names at an indent of 2 to 6 spaces, their text at 10.
fn parse_help(text: &str) -> Help {
    let usage = text
        .lines()
        .find(|l| l.starts_with("Usage: "))
        .expect("a usage line")
        .to_string();
    let mut entries = BTreeMap::new();
    let mut current: Option<(String, HelpEntry)> = None;
    // Where the entry's text is: its first paragraph, past it, or its possible values.
    let mut in_first_paragraph = false;
    let mut in_values = false;
    let mut in_entries = false;
    for line in text.lines() {
        if line == "Arguments:" || line == "Options:" {
            in_entries = true;
            continue;
        }
        if !in_entries {
            continue;
        }
        let indent = line.len() - line.trim_start().len();
        let body = line.trim();
        if indent == 0 && !body.is_empty() {
            // Text after the options (the preview's keys) ends them.
            in_entries = false;
            continue;
        }
        if (2..=6).contains(&indent) && body.starts_with(['-', '<', '[']) {
            if let Some((name, entry)) = current.take() {
                entries.insert(name, entry);
            }
            // A help without long texts prints each entry's meaning on its name's line.
            let (name, meaning) = match body.split_once("  ") {
                Some((name, meaning)) => (name, meaning.trim()),
                None => (body, ""),
            };
            let (meaning, default) = match meaning.rsplit_once(" [default: ") {
                Some((meaning, default)) => (meaning, default.strip_suffix(']')),
                None => (meaning, None),
            };
            let entry = HelpEntry {
                meaning: meaning.to_string(),
                default: default.map(str::to_string),
                ..HelpEntry::default()
            };
            current = Some((name.to_string(), entry));
            in_first_paragraph = meaning.is_empty();
            in_values = false;
            continue;
        }
        let Some((_, entry)) = current.as_mut() else {
            continue;
        };
        if body.is_empty() {
            in_first_paragraph = false;
        } else if let Some(default) = body
            .strip_prefix("[default: ")
            .and_then(|d| d.strip_suffix(']'))
        {
            entry.default = Some(default.to_string());
        } else if body == "Possible values:" {
            in_values = true;
        } else if in_values {
            let value = body.strip_prefix("- ").expect("a possible value");
            let (name, meaning) = value.split_once(':').expect("value: meaning");
            entry.values.push(format!("{name}: {}", meaning.trim()));
        } else if in_first_paragraph {
            if !entry.meaning.is_empty() {
                entry.meaning.push(' ');
            }
            entry.meaning.push_str(body);
        }
    }
    if let Some((name, entry)) = current {
        entries.insert(name, entry);
    }
    Help { usage, entries }
}

/// The cells of a markdown table row, trimmed.
fn cells(row: &str) -> Vec<String> {
    let inner = row.trim().trim_start_matches('|').trim_end_matches('|');
    inner.split(" | ").map(|c| c.trim().to_string()).collect()
}

/// A section of docs/cli.md from `heading` to the next `## `.
fn section<'a>(doc: &'a str, heading: &str) -> &'a str {
    let start = doc
        .find(&format!("\n{heading}\n"))
        .unwrap_or_else(|| panic!("docs/cli.md has no `{heading}`"));
    let rest = &doc[start + heading.len() + 2..];
    &rest[..rest.find("\n## ").unwrap_or(rest.len())]
}

fn doc() -> String {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/cli.md");
    std::fs::read_to_string(path).expect("docs/cli.md")
}

/// The commands `plume --help` lists, with what each does.
fn commands() -> Vec<(String, String)> {
    let text = help_text(&[]);
    let list = &text[text.find("Commands:\n").expect("a command list") + 10..];
    list.lines()
        .take_while(|l| !l.is_empty())
        .map(|l| {
            let (name, about) = l.trim().split_once(' ').expect("name and what it does");
            (name.to_string(), about.trim().to_string())
        })
        .collect()
}

#[test]
fn the_page_lists_every_command_with_what_it_does() {
    let doc = doc();
    let listed: Vec<(String, String)> = doc
        .lines()
        .filter(|l| l.starts_with("| [`"))
        .map(|l| {
            let row = cells(l);
            let name = row[0].trim_start_matches("[`");
            let name = &name[..name.find('`').expect("a quoted name")];
            (name.to_string(), row[1].clone())
        })
        .collect();
    assert_eq!(listed, commands(), "docs/cli.md's command table");
}

#[test]
fn every_command_section_matches_its_help() {
    let doc = doc();
    let mut checked = 0;
    for (name, _) in commands() {
        // `plume help --help` is refused: `plume help help` prints the help command's help.
        let help = match name.as_str() {
            "help" => parse_help(&help_text(&["help", "help"])),
            command => parse_help(&help_text(&[command])),
        };
        let text = section(&doc, &format!("## plume {name}"));
        let usage = text
            .lines()
            .find(|l| l.starts_with("Usage: "))
            .unwrap_or_else(|| panic!("`plume {name}` has no usage line in docs/cli.md"));
        assert_eq!(usage, help.usage, "`plume {name}`'s usage line");

        // The table of arguments and options (the preview's keys have a table of their own).
        let rows: BTreeMap<String, Vec<String>> = text
            .lines()
            .skip_while(|l| !(l.starts_with("| argument") || l.starts_with("| option")))
            .take_while(|l| l.starts_with('|'))
            .filter(|l| l.starts_with("| `"))
            .map(|l| {
                let row = cells(l);
                (row[0].trim_matches('`').to_string(), row)
            })
            .collect();
        let documented: Vec<&String> = rows.keys().collect();
        let printed: Vec<&String> = help.entries.keys().collect();
        assert_eq!(
            documented, printed,
            "`plume {name}`'s arguments and options"
        );

        for (entry_name, entry) in &help.entries {
            let row = &rows[entry_name];
            // The page moves a default that the meaning states ("(default: the top-level
            // one)", "; default WGPU_BACKEND or all") into its default column, and points at
            // the list of values below the table.
            let printed = entry
                .meaning
                .rsplit_once(" (default: ")
                .or_else(|| entry.meaning.rsplit_once("; default "))
                .map_or(entry.meaning.as_str(), |(meaning, _)| meaning);
            let documented = row[1].trim_end_matches(" (values below)");
            assert_eq!(
                documented, printed,
                "`plume {name}` `{entry_name}`: the page's meaning against --help's"
            );
            match &entry.default {
                // A value in code type, or words as they are (`the file's dt x 4, 2, 1`).
                Some(default) => assert!(
                    row[2] == format!("`{default}`") || row[2] == *default,
                    "`plume {name}` `{entry_name}`'s default: {} on the page, {default} in --help",
                    row[2]
                ),
                None => assert!(
                    !(row[2].starts_with('`')
                        && row[2].ends_with('`')
                        && row[2].matches('`').count() == 2),
                    "`plume {name}` `{entry_name}` has no default in --help, but the page gives {}",
                    row[2]
                ),
            }
            if !entry.values.is_empty() {
                let option = entry_name.split(' ').next().expect("an option's name");
                let list = text
                    .find(&format!("`{option}` values"))
                    .unwrap_or_else(|| panic!("`plume {name}` lists no `{option}` values"));
                let listed: Vec<String> = text[list..]
                    .lines()
                    .skip(2)
                    .take_while(|l| l.starts_with("- `"))
                    .map(|l| l.trim_start_matches("- `").replacen("`:", ":", 1))
                    .collect();
                assert_eq!(listed, entry.values, "`plume {name}` `{option}` values");
            }
            checked += 1;
        }
    }
    assert!(checked > 40, "only {checked} entries checked");
}

#[test]
fn the_preview_keys_are_those_its_help_lists() {
    let text = help_text(&["preview"]);
    let list = &text[text
        .find("Keys and mouse in the window:\n")
        .expect("the preview's help lists its keys")..];
    let printed: Vec<String> = list
        .lines()
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .map(|l| l.trim().to_string())
        .collect();
    let doc = doc();
    let documented: Vec<String> = section(&doc, "## plume preview")
        .lines()
        .skip_while(|l| !l.starts_with("| key or mouse |"))
        .skip(2)
        .take_while(|l| l.starts_with('|'))
        .map(|l| {
            let row = cells(l);
            format!("{}: {}", row[0].replace('`', ""), row[1])
        })
        .collect();
    assert!(printed.len() >= 10, "{printed:?}");
    assert_eq!(documented, printed, "docs/cli.md's preview keys");
}
