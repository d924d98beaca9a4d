//! Edit-to-diagnostics latency and memory of the language server on a
//! 5,000-line program (`mcl_syntax::gen::program(5000, 42)`).
//!
//! 1. In process, the server's own code path without the transport: a
//!    one-character edit inside a mission (`Database::set_text`), then the
//!    syntax diagnostics and the complete `check_file` diagnostics converted
//!    to LSP; against the same on a fresh database ("from scratch").
//! 2. End to end (with `--server PATH`, or `MCL_BIN`): the real `mcl lsp`
//!    over stdio, 1,000 edits, each waited for until its versioned
//!    diagnostics arrive; resident memory sampled every 100 edits.
//!
//! `cargo bench -p mcl-lsp --bench edit_latency -- --server target/release/mcl`
//! (see `mcl-lsp/benches/run.sh`).

use mcl_compiler::{Database, Db};
use mcl_lsp::analysis::{diagnostics, Analysis, DocInfo, World};
use serde_json::{json, Value};
use std::io::{BufRead, BufReader, Read, Write};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::Instant;
use tower_lsp_server::ls_types::Uri;

/// Every diagnostic of `check_file`, converted to LSP values (the compiler's
/// part of the server's semantic diagnostics; `diagnostics::full` adds the
/// coordination analysis of the constraints, measured apart).
fn compiler_diagnostics(a: &Analysis<'_>, f: mcl_compiler::SourceFile) -> Vec<tower_lsp_server::ls_types::Diagnostic> {
    mcl_compiler::check_file(a.db, f).iter().map(|fd| diagnostics::to_lsp(a, f, &fd.diag)).collect()
}

fn percentile(v: &mut [f64], p: f64) -> f64 {
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let i = ((v.len() as f64 - 1.0) * p).round() as usize;
    v[i.min(v.len() - 1)]
}

/// Byte offsets just after `{` of every mission line (edit sites).
fn mission_sites(text: &str) -> Vec<usize> {
    let mut sites = Vec::new();
    let mut off = 0;
    for line in text.split_inclusive('\n') {
        if (line.starts_with("mission") || line.starts_with("mcl_plan_op")) && line.trim_end().ends_with('{') {
            sites.push(off + line.trim_end().len());
        }
        off += line.len();
    }
    sites
}

struct Rng(u64);
impl Rng {
    fn below(&mut self, n: usize) -> usize {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 % n as u64) as usize
    }
}

fn in_process(text: &str) {
    let path = PathBuf::from("/bench/program.mcl");
    let uri = Uri::from_file_path(&path).unwrap();
    let mut world = World::default();
    world.docs.insert(path.clone(), DocInfo { uri, path: path.clone(), version: 1 });
    let sites = mission_sites(text);
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);

    // From scratch: a fresh database, then every diagnostic.
    let mut scratch = Vec::new();
    for _ in 0..30 {
        let t = Instant::now();
        let mut db = Database::new();
        let f = db.set_text(&path, text.to_string());
        let a = Analysis::new(&db, &world);
        let d = compiler_diagnostics(&a, f);
        assert!(
            d.is_empty(),
            "{:?}",
            d.iter().map(|d| (&d.code, &d.message, d.range.start)).take(5).collect::<Vec<_>>()
        );
        scratch.push(t.elapsed().as_secs_f64() * 1e3);
    }

    // Incremental: one character inserted (then removed) inside a mission.
    let mut db = Database::new();
    let f = db.set_text(&path, text.to_string());
    compiler_diagnostics(&Analysis::new(&db, &world), f);
    let mut cur = text.to_string();
    let (mut syntax, mut full) = (Vec::new(), Vec::new());
    for i in 0..400 {
        let site = sites[rng.below(sites.len())];
        if i % 2 == 0 {
            cur.insert(site, ' ');
        } else {
            cur = text.to_string();
        }
        let t = Instant::now();
        db.set_text(&path, cur.clone());
        let a = Analysis::new(&db, &world);
        let s = diagnostics::syntax(&a, f);
        syntax.push(t.elapsed().as_secs_f64() * 1e3);
        let d = compiler_diagnostics(&a, f);
        full.push(t.elapsed().as_secs_f64() * 1e3);
        assert!(s.is_empty() && d.is_empty());
        let _ = db.file(&path);
    }
    // An edit that makes an error: a call's name changed by one letter.
    let call = text.find("    Void() : start").unwrap() + 4;
    let mut errs = Vec::new();
    for i in 0..100 {
        let mut t2 = text.to_string();
        if i % 2 == 0 {
            t2.replace_range(call..call + 1, "W");
        }
        let t = Instant::now();
        db.set_text(&path, t2);
        let d = compiler_diagnostics(&Analysis::new(&db, &world), f);
        errs.push(t.elapsed().as_secs_f64() * 1e3);
        assert_eq!(d.len(), if i % 2 == 0 { 1 } else { 0 });
    }
    let sp50 = percentile(&mut scratch, 0.5);
    let (f50, f99) = (percentile(&mut full, 0.5), percentile(&mut full, 0.99));
    println!("in-process, {} lines, {} bytes:", text.lines().count(), text.len());
    println!("  from scratch (fresh database):  p50 {sp50:.2} ms  p99 {:.2} ms", percentile(&mut scratch, 0.99));
    println!(
        "  edit -> syntax diagnostics:     p50 {:.2} ms  p99 {:.2} ms",
        percentile(&mut syntax, 0.5),
        percentile(&mut syntax, 0.99)
    );
    println!("  edit -> all diagnostics:        p50 {f50:.2} ms  p99 {f99:.2} ms");
    println!(
        "  edit making an error -> all:    p50 {:.2} ms  p99 {:.2} ms",
        percentile(&mut errs, 0.5),
        percentile(&mut errs, 0.99)
    );
    println!("  speed-up over scratch (p50):    {:.1}x", sp50 / f50);
    // Where the time goes: the parse alone, and the parse of one mission.
    let mut parse = Vec::new();
    let mut lex = Vec::new();
    let mut item = Vec::new();
    let one = &text[sites[sites.len() / 2] - 20..];
    let one = &one[..one.find("\n}\n").map_or(one.len(), |i| i + 3)];
    for _ in 0..50 {
        let t = Instant::now();
        std::hint::black_box(mcl_syntax::parse(text));
        parse.push(t.elapsed().as_secs_f64() * 1e3);
        let t = Instant::now();
        std::hint::black_box(mcl_syntax::lexer::lex(text));
        lex.push(t.elapsed().as_secs_f64() * 1e3);
        let t = Instant::now();
        std::hint::black_box(mcl_syntax::parse(one));
        item.push(t.elapsed().as_secs_f64() * 1e3);
    }
    println!("  mcl_syntax::parse, whole file:  p50 {:.2} ms", percentile(&mut parse, 0.5));
    println!("  mcl_syntax::lexer::lex, whole:  p50 {:.2} ms", percentile(&mut lex, 0.5));
    println!(
        "  mcl_syntax::parse, one mission: p50 {:.3} ms ({} lines)",
        percentile(&mut item, 0.5),
        one.lines().count()
    );

    // Requests on the same file (warm database, as after the edits above).
    db.set_text(&path, text.to_string());
    let a = Analysis::new(&db, &world);
    compiler_diagnostics(&a, f);
    let call = text.rfind("Goto( [x, y] )").unwrap() + 1;
    let stmt = sites[sites.len() / 2] + 5;
    let time = |name: &str, run: &mut dyn FnMut()| {
        let mut v = Vec::new();
        for _ in 0..20 {
            let t = Instant::now();
            run();
            v.push(t.elapsed().as_secs_f64() * 1e3);
        }
        println!("  {name:<31} p50 {:.2} ms  p99 {:.2} ms", percentile(&mut v, 0.5), percentile(&mut v, 0.99));
    };
    use mcl_lsp::analysis::{completion, hover, navigation, outline, semantic};
    time("hover (task call):", &mut || assert!(hover::hover(&a, f, call).is_some()));
    time("definition (task call):", &mut || assert_eq!(navigation::goto_definition(&a, f, call).len(), 1));
    let uses = navigation::references(&a, f, call, true).len();
    time(&format!("references (`Goto`, {uses}):"), &mut || {
        assert!(navigation::references(&a, f, call, true).len() > 100)
    });
    time("completion (statement):", &mut || assert!(!completion::completion(&a, f, stmt, true).is_empty()));
    time("semantic tokens (full):", &mut || assert!(!semantic::semantic_tokens(&a, f).is_empty()));
    time("document symbols:", &mut || assert!(!outline::document_symbols(&a, f).is_empty()));
    time("folding ranges:", &mut || assert!(!outline::folding_ranges(&a, f).is_empty()));
}

struct Client {
    stdin: std::process::ChildStdin,
    out: BufReader<std::process::ChildStdout>,
}

impl Client {
    fn send(&mut self, v: &Value) {
        let b = serde_json::to_vec(v).unwrap();
        write!(self.stdin, "Content-Length: {}\r\n\r\n", b.len()).unwrap();
        self.stdin.write_all(&b).unwrap();
        self.stdin.flush().unwrap();
    }
    fn recv(&mut self) -> Value {
        let mut len = 0;
        loop {
            let mut l = String::new();
            self.out.read_line(&mut l).unwrap();
            let l = l.trim();
            if l.is_empty() {
                break;
            }
            if let Some(v) = l.strip_prefix("Content-Length:") {
                len = v.trim().parse().unwrap();
            }
        }
        let mut b = vec![0; len];
        self.out.read_exact(&mut b).unwrap();
        serde_json::from_slice(&b).unwrap()
    }
}

fn rss_kib(pid: u32) -> u64 {
    let s = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap_or_default();
    s.lines().find(|l| l.starts_with("VmRSS:")).and_then(|l| l.split_whitespace().nth(1)?.parse().ok()).unwrap_or(0)
}

/// A server started and initialized over stdio.
fn start(bin: &str, dir: &std::path::Path) -> (std::process::Child, Client) {
    let mut child = Command::new(bin)
        .arg("lsp")
        .env("XDG_CACHE_HOME", dir.join("cache"))
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("start the server");
    let mut c = Client { stdin: child.stdin.take().unwrap(), out: BufReader::new(child.stdout.take().unwrap()) };
    c.send(&json!({"jsonrpc": "2.0", "id": 1, "method": "initialize", "params": {"processId": null, "rootUri": null, "capabilities": {}}}));
    while c.recv().get("id") != Some(&json!(1)) {}
    c.send(&json!({"jsonrpc": "2.0", "method": "initialized", "params": {}}));
    (child, c)
}

/// Waits for the first diagnostics of `version`; checks that they are the
/// expected ones (none, or one E0101: the compiler's checks ran on the edit).
fn wait(c: &mut Client, version: i64, error: bool) {
    loop {
        let m = c.recv();
        if m["method"] == "textDocument/publishDiagnostics" && m["params"]["version"] == version {
            let d = m["params"]["diagnostics"].as_array().unwrap();
            if error {
                assert!(d.len() == 1 && d[0]["code"] == "E0101", "{m}");
            } else {
                assert!(d.is_empty(), "{m}");
            }
            return;
        }
    }
}

fn end_to_end(bin: &str, text: &str) {
    let dir = std::env::temp_dir().join(format!("mcl-lsp-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("program.mcl");
    std::fs::write(&file, text).unwrap();
    let uri = format!("file://{}", file.display());
    let open = json!({"jsonrpc": "2.0", "method": "textDocument/didOpen", "params": {"textDocument": {"uri": uri, "languageId": "mcl", "version": 1, "text": text}}});

    // From scratch: a fresh server opens the file (every parse and check).
    let mut scratch = Vec::new();
    for _ in 0..5 {
        let (mut child, mut c) = start(bin, &dir);
        let t = Instant::now();
        c.send(&open);
        wait(&mut c, 1, false);
        scratch.push(t.elapsed().as_secs_f64() * 1e3);
        let _ = child.kill();
        let _ = child.wait();
    }

    let (mut child, mut c) = start(bin, &dir);
    let pid = child.id();
    let rss_start = rss_kib(pid);
    c.send(&open);
    wait(&mut c, 1, false);
    let rss_open = rss_kib(pid);
    let sites = mission_sites(text);
    // Task calls inside missions: `Goto(` at the start of a statement.
    let calls: Vec<usize> = text.match_indices("    Goto( ").map(|(i, _)| i + 4).filter(|&i| i > sites[0]).collect();
    let idx = mcl_syntax::LineIndex::new(text);
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    let (mut blank, mut semantic) = (Vec::new(), Vec::new());
    let mut rss = Vec::new();
    let mut undo: Option<(u32, u32, &str, bool)> = None;
    for i in 0..1000i64 {
        let version = i + 2;
        // Edits 0..500: a space inserted inside a mission, then removed (the
        // checks' results do not change). Edits 500..1000: a call's task
        // renamed `Goto` -> `Woto` (E0101 appears), then back (it goes).
        let (change, error, is_blank) = match undo.take() {
            None if i < 500 => {
                let (l, ch) = idx.utf16_position(text, sites[rng.below(sites.len())]);
                undo = Some((l, ch, "", true));
                (
                    json!({"range": {"start": {"line": l, "character": ch}, "end": {"line": l, "character": ch}}, "text": " "}),
                    false,
                    true,
                )
            }
            None => {
                let (l, ch) = idx.utf16_position(text, calls[rng.below(calls.len())]);
                undo = Some((l, ch, "G", false));
                (
                    json!({"range": {"start": {"line": l, "character": ch}, "end": {"line": l, "character": ch + 1}}, "text": "W"}),
                    true,
                    false,
                )
            }
            Some((l, ch, back, is_blank)) => {
                let end = ch + 1;
                (
                    json!({"range": {"start": {"line": l, "character": ch}, "end": {"line": l, "character": end}}, "text": back}),
                    false,
                    is_blank,
                )
            }
        };
        let t = Instant::now();
        c.send(&json!({"jsonrpc": "2.0", "method": "textDocument/didChange", "params": {"textDocument": {"uri": uri, "version": version}, "contentChanges": [change]}}));
        wait(&mut c, version, error);
        let ms = t.elapsed().as_secs_f64() * 1e3;
        if is_blank {
            blank.push(ms);
        } else {
            semantic.push(ms);
        }
        if (i + 1) % 100 == 0 {
            rss.push(rss_kib(pid));
        }
    }
    c.send(&json!({"jsonrpc": "2.0", "id": 2, "method": "shutdown", "params": null}));
    while c.recv().get("id") != Some(&json!(2)) {}
    c.send(&json!({"jsonrpc": "2.0", "method": "exit", "params": null}));
    let status = child.wait().unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    let sp50 = percentile(&mut scratch, 0.5);
    let s50 = percentile(&mut semantic, 0.5);
    println!("end to end (`{bin} lsp` over stdio, 1,000 edits, each waited for):");
    println!("  from scratch (fresh server, didOpen -> diagnostics): p50 {sp50:.2} ms (5 runs)");
    println!(
        "  blank edit -> publishDiagnostics:        p50 {:.2} ms  p99 {:.2} ms  max {:.2} ms",
        percentile(&mut blank, 0.5),
        percentile(&mut blank, 0.99),
        blank.iter().cloned().fold(0.0, f64::max)
    );
    println!(
        "  E0101 made/fixed -> publishDiagnostics:  p50 {s50:.2} ms  p99 {:.2} ms  max {:.2} ms",
        percentile(&mut semantic, 0.99),
        semantic.iter().cloned().fold(0.0, f64::max)
    );
    println!("  speed-up of a semantic edit over scratch (p50): {:.1}x", sp50 / s50);
    println!("  resident memory: {} MiB after start, {} MiB after open", rss_start / 1024, rss_open / 1024);
    println!(
        "  resident memory every 100 edits (MiB): {}",
        rss.iter().map(|k| format!("{:.1}", *k as f64 / 1024.0)).collect::<Vec<_>>().join(" ")
    );
    println!("  exit status: {status}");
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let text = mcl_syntax::gen::program(5000, 42);
    assert!(mcl_syntax::parse(&text).errors.is_empty());
    in_process(&text);
    let bin = args
        .iter()
        .position(|a| a == "--server")
        .and_then(|i| args.get(i + 1).cloned())
        .or_else(|| std::env::var("MCL_BIN").ok());
    match bin {
        Some(b) => end_to_end(&b, &text),
        None => println!("(end-to-end part skipped: pass --server PATH or set MCL_BIN)"),
    }
}
