//! The long explanations of `mcl explain CODE` (mcl-compiler/explain/*.md):
//! every code has one, with an `## Example` that triggers the code and a
//! `## Fix` that removes it. Both programs are checked for real, in an
//! in-memory database where `examples/vehicle.mcl` sits next to them so that
//! `import "vehicle.mcl";` resolves.

use mcl_compiler::codes::{self, CodeInfo};
use mcl_compiler::{check_file, Database, FileDiagnostic};
use std::path::PathBuf;

const VEHICLE: &str = include_str!("../../examples/vehicle.mcl");

/// A folder that does not exist on disk: every file in it comes from `set_text`.
fn virtual_dir(code: &str, section: &str) -> PathBuf {
    let root =
        if cfg!(windows) { PathBuf::from(r"C:\mcl-explain-virtual") } else { PathBuf::from("/mcl-explain-virtual") };
    root.join(code).join(section.to_ascii_lowercase())
}

/// The text of a `## name` section (up to the next `## ` heading).
fn section<'a>(md: &'a str, name: &str) -> Option<&'a str> {
    let heading = format!("## {name}");
    let mut start = None;
    let mut offset = 0;
    for line in md.split_inclusive('\n') {
        match start {
            None if line.trim_end() == heading => start = Some(offset + line.len()),
            None => {}
            Some(s) if line.starts_with("## ") => return Some(&md[s..offset]),
            Some(_) => {}
        }
        offset += line.len();
    }
    start.map(|s| &md[s..])
}

/// The ```mcl code blocks of a piece of Markdown.
fn mcl_blocks(text: &str) -> Vec<String> {
    let mut blocks = Vec::new();
    let mut current: Option<String> = None;
    for line in text.lines() {
        match &mut current {
            None if line.trim_start().starts_with("```mcl") => current = Some(String::new()),
            None => {}
            Some(b) if line.trim_start().starts_with("```") => {
                blocks.push(std::mem::take(b));
                current = None;
            }
            Some(b) => {
                b.push_str(line);
                b.push('\n');
            }
        }
    }
    assert!(current.is_none(), "unterminated code block");
    blocks
}

/// The one ```mcl block of a section.
fn program_of(info: &CodeInfo, name: &str) -> String {
    let text = section(info.explanation, name).unwrap_or_else(|| panic!("{}: no `## {name}` section", info.code));
    let mut blocks = mcl_blocks(text);
    assert_eq!(blocks.len(), 1, "{}: `## {name}` must hold exactly one ```mcl block", info.code);
    blocks.remove(0)
}

/// The file name of a program: `// survey.mcl` on its first line names it,
/// otherwise `mission.mcl`.
fn file_name(src: &str) -> String {
    let first = src.lines().next().unwrap_or("").trim();
    match first.strip_prefix("//").map(str::trim) {
        Some(n) if n.ends_with(".mcl") && !n.contains(char::is_whitespace) => n.to_string(),
        _ => "mission.mcl".to_string(),
    }
}

/// Checks `src` as the root of a program in a fresh database.
fn check(code: &str, section: &str, src: &str) -> Vec<FileDiagnostic> {
    let mut db = Database::new();
    let dir = virtual_dir(code, section);
    db.set_text(&dir.join("vehicle.mcl"), VEHICLE);
    let file = db.set_text(&dir.join(file_name(src)), src);
    check_file(&db, file).clone()
}

fn describe(diags: &[FileDiagnostic]) -> String {
    diags
        .iter()
        .map(|d| format!("  {} {}: {}", d.diag.severity.as_str(), d.diag.code, d.diag.message))
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn every_code_has_an_explanation_with_example_and_fix() {
    let mut problems = Vec::new();
    for info in codes::ALL {
        let title = format!("# {}: {}", info.code, info.title);
        if info.explanation.lines().next() != Some(title.as_str()) {
            problems.push(format!("{}: the first line must be `{title}`", info.code));
        }
        if info.explanation.lines().any(|l| l.trim() == "TODO") {
            problems.push(format!("{}: still a TODO", info.code));
        }
        for name in ["Example", "Fix"] {
            match section(info.explanation, name) {
                None => problems.push(format!("{}: no `## {name}` section", info.code)),
                Some(text) if mcl_blocks(text).len() != 1 => {
                    problems.push(format!("{}: `## {name}` must hold exactly one ```mcl block", info.code))
                }
                Some(_) => {}
            }
        }
        let example = info.explanation.find("## Example");
        let fix = info.explanation.find("## Fix");
        if let (Some(e), Some(f)) = (example, fix) {
            if e > f {
                problems.push(format!("{}: `## Example` must come before `## Fix`", info.code));
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn examples_trigger_their_code_and_fixes_remove_it() {
    let mut problems = Vec::new();
    for info in codes::ALL {
        if codes::COORDINATION.contains(&info.code) || codes::LINK.contains(&info.code) {
            continue; // checked by mcl-coord/tests/check.rs and mcl-coord/tests/link_report.rs
        }
        let example = program_of(info, "Example");
        let diags = check(info.code, "Example", &example);
        if !diags.iter().any(|d| d.diag.code == info.code) {
            problems.push(format!(
                "{}: the example does not produce {}; it produces:\n{}",
                info.code,
                info.code,
                describe(&diags)
            ));
        }
        let fix = program_of(info, "Fix");
        let diags = check(info.code, "Fix", &fix);
        if diags.iter().any(|d| d.diag.code == info.code || d.diag.is_error()) {
            problems.push(format!("{}: the fix still produces:\n{}", info.code, describe(&diags)));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn codes_are_sorted_unique_and_well_formed() {
    let all: Vec<&str> = codes::ALL.iter().map(|c| c.code).collect();
    // Sorted by number, whatever the letter (W0015 is a syntax code).
    let mut sorted = all.clone();
    sorted.sort_by_key(|c| (c[1..].to_string(), c.to_string()));
    sorted.dedup_by_key(|c| c[1..].to_string());
    assert_eq!(all, sorted, "codes::ALL must be sorted by number, each number once");
    for c in &all {
        assert_eq!(c.len(), 5, "{c}");
        assert!(c.starts_with('E') || c.starts_with('W'), "{c}");
        assert!(c[1..].chars().all(|d| d.is_ascii_digit()), "{c}");
    }
}

#[test]
fn lookup_is_lenient() {
    assert_eq!(codes::lookup("e101").map(|c| c.code), Some("E0101"));
    assert_eq!(codes::lookup("E0101").map(|c| c.code), Some("E0101"));
    assert_eq!(codes::lookup(" w901 ").map(|c| c.code), Some("W0901"));
    assert_eq!(codes::lookup("e0001").map(|c| c.code), Some("E0001"));
    assert!(codes::lookup("E9999").is_none());
    assert!(codes::lookup("mission").is_none());
    assert!(codes::lookup("").is_none());
    for info in codes::ALL {
        assert_eq!(codes::lookup(&info.code.to_ascii_lowercase()).map(|c| c.code), Some(info.code));
    }
}

#[test]
fn the_virtual_folder_resolves_imports() {
    // Guards the harness itself: a mission that uses the vehicle is clean.
    let src = "import \"vehicle.mcl\";\n\nmission {\n    Depth( 15, \"achieve\" ) ;\n    Surface()\n}\n";
    let diags = check("harness", "Fix", src);
    assert!(diags.is_empty(), "{}", describe(&diags));
    assert_eq!(file_name("// survey.mcl\nmission { Void() }"), "survey.mcl");
    assert_eq!(file_name("import \"vehicle.mcl\";"), "mission.mcl");
}
