//! End-to-end tests of `mcl lsp`: the real binary, driven over stdio as an
//! editor drives it (Content-Length framed JSON-RPC). Cursor positions come
//! from `$0` markers in the fixture texts; responses are insta snapshots
//! with the workspace folder shown as `file:///WORKSPACE`.

use serde_json::{json, Value};
use std::collections::VecDeque;
use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{channel, Receiver, RecvTimeoutError};
use std::time::{Duration, Instant};

const TIMEOUT: Duration = Duration::from_secs(30);

const VEHICLE: &str = r#"// A small vehicle.
actions {
    enableGoto = GotoPrimitive( c: enable, v: way-point );
    disableGoto = GotoPrimitive( c: disable );
    enableDepth = DepthPrimitive( c: enable, v: depth, v: mode );
    disableDepth = DepthPrimitive( c: disable );
}

events {
    eventGotoOk; eventGotoFail;
    eventDepthOk; eventDepthFail;
}

tasks {
    // Go to one way-point.
    Goto( way-point ): AchieveOneGoal {
        a: enableGoto -> T0;
        a: disableGoto -> T1, T6, T7;
        e: eventGotoOk -> T2;
        e: eventGotoFail -> T3;
    }
    Depth( depth, mode ): AchieveOneGoal {
        a: enableDepth -> T0;
        a: disableDepth -> T1, T6, T7;
        e: eventDepthOk -> T2;
        e: eventDepthFail -> T3;
    }
    Void(): Instant { }
}
"#;

const MISSION: &str = r#"import "vehicle.mcl";

mission : auv {
    Depth( 15, "achieve" ) : dive ;
    parallel {
        Depth( 15, "keep" )
    } or {
        Goto( [24, 12] ) : go
    }
}

mission : asc {
    Void() : wait ;
    Goto( [0, 0] )
}

constraints {
    mutex { auv:go, asc:wait } = 1
}
"#;

/// A fresh workspace folder with the given files.
fn workspace(name: &str, files: &[(&str, &str)]) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("lsp").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for (n, t) in files {
        std::fs::write(dir.join(n), t).unwrap();
    }
    dir.canonicalize().unwrap()
}

/// Splits the `$0` marker out of a text: the text and the marker's position.
fn marker(text: &str) -> (String, Value) {
    let i = text.find("$0").expect("a $0 marker");
    let before = &text[..i];
    let line = before.matches('\n').count();
    let col: usize = before.rsplit('\n').next().unwrap().chars().map(char::len_utf16).sum();
    (text.replacen("$0", "", 1), json!({"line": line, "character": col}))
}

/// The position of the first `needle` in `text`, plus `delta` characters.
fn pos(text: &str, needle: &str, delta: usize) -> Value {
    let i = text.find(needle).unwrap_or_else(|| panic!("`{needle}` not found")) + delta;
    marker(&format!("{}$0{}", &text[..i], &text[i..])).1
}

struct Lsp {
    child: Child,
    stdin: ChildStdin,
    rx: Receiver<Value>,
    next_id: i64,
    /// Notifications read while waiting for something else.
    stash: VecDeque<Value>,
    root: PathBuf,
    cache: PathBuf,
}

fn uri_of(path: &Path) -> String {
    format!("file://{}", path.display())
}

impl Lsp {
    fn start(root: &Path) -> Lsp {
        let cache = root.parent().unwrap().join(format!("{}-cache", root.file_name().unwrap().to_string_lossy()));
        let mut child = Command::new(env!("CARGO_BIN_EXE_mcl"))
            .arg("lsp")
            .env("XDG_CACHE_HOME", &cache)
            .current_dir(root)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("start mcl lsp");
        let stdin = child.stdin.take().unwrap();
        let stdout = child.stdout.take().unwrap();
        let (tx, rx) = channel();
        std::thread::spawn(move || {
            let mut r = BufReader::new(stdout);
            loop {
                let mut len = 0usize;
                loop {
                    let mut line = String::new();
                    if r.read_line(&mut line).unwrap_or(0) == 0 {
                        return;
                    }
                    let line = line.trim();
                    if line.is_empty() {
                        break;
                    }
                    if let Some(v) = line.strip_prefix("Content-Length:") {
                        len = v.trim().parse().unwrap();
                    }
                }
                let mut body = vec![0u8; len];
                if r.read_exact(&mut body).is_err() {
                    return;
                }
                if tx.send(serde_json::from_slice::<Value>(&body).unwrap()).is_err() {
                    return;
                }
            }
        });
        Lsp { child, stdin, rx, next_id: 0, stash: VecDeque::new(), root: root.to_path_buf(), cache }
    }

    fn uri(&self, name: &str) -> String {
        uri_of(&self.root.join(name))
    }

    fn send(&mut self, msg: &Value) {
        let body = serde_json::to_vec(msg).unwrap();
        let _ = write!(self.stdin, "Content-Length: {}\r\n\r\n", body.len());
        let _ = self.stdin.write_all(&body);
        let _ = self.stdin.flush();
    }

    fn send_raw(&mut self, body: &[u8]) {
        let _ = write!(self.stdin, "Content-Length: {}\r\n\r\n", body.len());
        let _ = self.stdin.write_all(body);
        let _ = self.stdin.flush();
    }

    fn notify(&mut self, method: &str, params: Value) {
        self.send(&json!({"jsonrpc": "2.0", "method": method, "params": params}));
    }

    /// Reads one message; answers the server's own requests (registrations, refreshes).
    fn recv(&mut self, deadline: Instant) -> Option<Value> {
        let left = deadline.saturating_duration_since(Instant::now());
        match self.rx.recv_timeout(left) {
            Ok(m) => {
                if m.get("method").is_some() && m.get("id").is_some() {
                    let id = m["id"].clone();
                    self.send(&json!({"jsonrpc": "2.0", "id": id, "result": null}));
                }
                Some(m)
            }
            Err(RecvTimeoutError::Timeout) => None,
            Err(RecvTimeoutError::Disconnected) => panic!("the server closed its output"),
        }
    }

    /// Sends a request and returns the whole response (`result` or `error`).
    fn request_full(&mut self, method: &str, params: Value) -> Value {
        self.next_id += 1;
        let id = self.next_id;
        self.send(&json!({"jsonrpc": "2.0", "id": id, "method": method, "params": params}));
        let deadline = Instant::now() + TIMEOUT;
        loop {
            let m = self.recv(deadline).unwrap_or_else(|| panic!("no answer to {method}"));
            if m.get("id") == Some(&json!(id)) && m.get("method").is_none() {
                return m;
            }
            self.stash.push_back(m);
        }
    }

    fn request(&mut self, method: &str, params: Value) -> Value {
        let r = self.request_full(method, params);
        assert!(r.get("error").is_none(), "{method} failed: {r}");
        r["result"].clone()
    }

    /// The next notification `method` that satisfies `pred`.
    fn wait_for(&mut self, method: &str, pred: impl Fn(&Value) -> bool) -> Value {
        if let Some(i) = self.stash.iter().position(|m| m["method"] == method && pred(&m["params"])) {
            let m = self.stash.remove(i).unwrap();
            return m["params"].clone();
        }
        let deadline = Instant::now() + TIMEOUT;
        loop {
            let m = self.recv(deadline).unwrap_or_else(|| panic!("no {method} notification came"));
            if m["method"] == method && pred(&m["params"]) {
                return m["params"].clone();
            }
            self.stash.push_back(m);
        }
    }

    /// The diagnostics of `name` once they are complete for `version`
    /// (syntax errors may come first; the last publication wins).
    fn diagnostics(&mut self, name: &str, version: Option<i64>) -> Value {
        let uri = self.uri(name);
        let matches = |p: &Value| p["uri"] == uri.as_str() && p.get("version").and_then(Value::as_i64) == version;
        let mut last = self.wait_for("textDocument/publishDiagnostics", matches);
        // Anything more for the same document and version within a short while replaces it.
        let deadline = Instant::now() + Duration::from_millis(300);
        while let Some(m) = self.recv(deadline) {
            if m["method"] == "textDocument/publishDiagnostics" && matches(&m["params"]) {
                last = m["params"].clone();
            } else {
                self.stash.push_back(m);
            }
        }
        self.stash.retain(|m| !(m["method"] == "textDocument/publishDiagnostics" && matches(&m["params"])));
        last
    }

    fn initialize(&mut self, capabilities: Value) -> Value {
        let root = uri_of(&self.root);
        let r = self.request(
            "initialize",
            json!({"processId": null, "rootUri": root, "capabilities": capabilities,
                   "workspaceFolders": [{"uri": root, "name": "ws"}]}),
        );
        self.notify("initialized", json!({}));
        r
    }

    fn open(&mut self, name: &str, text: &str) {
        let uri = self.uri(name);
        self.notify(
            "textDocument/didOpen",
            json!({"textDocument": {"uri": uri, "languageId": "mcl", "version": 1, "text": text}}),
        );
    }

    fn change(&mut self, name: &str, version: i64, changes: Value) {
        let uri = self.uri(name);
        self.notify(
            "textDocument/didChange",
            json!({"textDocument": {"uri": uri, "version": version}, "contentChanges": changes}),
        );
    }

    fn at(&self, name: &str, position: Value) -> Value {
        json!({"textDocument": {"uri": self.uri(name)}, "position": position})
    }

    /// Shows paths relative to the workspace, for snapshots.
    fn stable(&self, v: Value) -> Value {
        let s = serde_json::to_string(&v).unwrap();
        let s = s.replace(&uri_of(&self.root), "file:///WORKSPACE").replace(&uri_of(&self.cache), "file:///CACHE");
        serde_json::from_str(&s).unwrap()
    }

    /// `shutdown` then `exit`; returns the exit status.
    fn shutdown(mut self) -> i32 {
        let r = self.request_full("shutdown", Value::Null);
        assert_eq!(r["result"], Value::Null, "{r}");
        self.notify("exit", Value::Null);
        let deadline = Instant::now() + TIMEOUT;
        loop {
            if let Some(s) = self.child.try_wait().unwrap() {
                return s.code().unwrap_or(-1);
            }
            assert!(Instant::now() < deadline, "the server did not exit");
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

impl Drop for Lsp {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn client_caps() -> Value {
    json!({
        "textDocument": {
            "completion": {"completionItem": {"snippetSupport": true}},
            "publishDiagnostics": {"relatedInformation": true, "versionSupport": true},
            "documentSymbol": {"hierarchicalDocumentSymbolSupport": true}
        },
        "workspace": {"didChangeWatchedFiles": {"dynamicRegistration": true}}
    })
}

#[test]
fn lifecycle_and_versioned_diagnostics() {
    let broken = MISSION.replace("Goto( [0, 0] )", "Goto( 0, 0 )");
    let root = workspace("lifecycle", &[("vehicle.mcl", VEHICLE), ("mission.mcl", &broken)]);
    let mut lsp = Lsp::start(&root);
    let init = lsp.initialize(client_caps());
    insta::assert_json_snapshot!("initialize", init);

    lsp.open("mission.mcl", &broken);
    let d = lsp.diagnostics("mission.mcl", Some(1));
    let d = lsp.stable(d);
    insta::assert_json_snapshot!("open_diagnostics", d);
    // The imported file is analysed too (no version: it is not open).
    let v = lsp.diagnostics("vehicle.mcl", None);
    assert_eq!(v["diagnostics"], json!([]));

    // Fix the call with an incremental change: `0, 0` -> `[0, 0]`.
    let start = pos(&broken, "0, 0 )", 0);
    let end = pos(&broken, "0, 0 )", 4);
    lsp.change("mission.mcl", 2, json!([{"range": {"start": start, "end": end}, "text": "[0, 0]"}]));
    let d = lsp.diagnostics("mission.mcl", Some(2));
    assert_eq!(d["diagnostics"], json!([]), "{d}");

    // A syntax error: an unclosed `(`.
    let p = pos(MISSION, "Void() : wait", 5);
    lsp.change("mission.mcl", 3, json!([{"range": {"start": p, "end": p}, "text": "("}]));
    let d = lsp.diagnostics("mission.mcl", Some(3));
    let codes: Vec<&str> = d["diagnostics"].as_array().unwrap().iter().map(|x| x["code"].as_str().unwrap()).collect();
    assert!(codes.contains(&"E0011"), "{d}");

    // A whole-text change, then close: the diagnostics are cleared.
    lsp.change("mission.mcl", 4, json!([{"text": MISSION}]));
    assert_eq!(lsp.diagnostics("mission.mcl", Some(4))["diagnostics"], json!([]));
    let uri = lsp.uri("mission.mcl");
    lsp.notify("textDocument/didClose", json!({"textDocument": {"uri": uri}}));
    let cleared = lsp.diagnostics("mission.mcl", None);
    assert_eq!(cleared["diagnostics"], json!([]));
    assert_eq!(lsp.shutdown(), 0);
}

#[test]
fn hover_definition_references() {
    let root = workspace("navigation", &[("vehicle.mcl", VEHICLE), ("mission.mcl", MISSION)]);
    let mut lsp = Lsp::start(&root);
    lsp.initialize(client_caps());
    lsp.open("mission.mcl", MISSION);
    lsp.diagnostics("mission.mcl", Some(1));

    let (_, p) = marker(&MISSION.replace("Goto( [24", "Go$0to( [24"));
    let hover = lsp.request("textDocument/hover", lsp.at("mission.mcl", p.clone()));
    insta::assert_json_snapshot!("hover_task", hover);
    let def = lsp.request("textDocument/definition", lsp.at("mission.mcl", p.clone()));
    insta::assert_json_snapshot!("definition_task", lsp.stable(def));
    let mut params = lsp.at("mission.mcl", p);
    params["context"] = json!({"includeDeclaration": true});
    let refs = lsp.request("textDocument/references", params);
    insta::assert_json_snapshot!("references_task", lsp.stable(refs));

    // A label in a constraint goes to the labelled call.
    let (_, p) = marker(&MISSION.replace("asc:wait }", "asc:wa$0it }"));
    let def = lsp.request("textDocument/definition", lsp.at("mission.mcl", p));
    assert_eq!(lsp.stable(def)["range"]["start"], json!({"line": 12, "character": 13}));

    // A keyword: what the control structure does.
    let (_, p) = marker(&MISSION.replace("parallel {", "paral$0lel {"));
    let hover = lsp.request("textDocument/hover", lsp.at("mission.mcl", p));
    assert!(hover["contents"]["value"].as_str().unwrap().contains("**parallel-or**"), "{hover}");
    assert_eq!(lsp.shutdown(), 0);
}

#[test]
fn rename_across_files() {
    let root = workspace("rename", &[("vehicle.mcl", VEHICLE), ("mission.mcl", MISSION)]);
    let mut lsp = Lsp::start(&root);
    lsp.initialize(client_caps());
    lsp.open("mission.mcl", MISSION);
    let (_, p) = marker(&MISSION.replace("Goto( [0", "Go$0to( [0"));
    let prep = lsp.request("textDocument/prepareRename", lsp.at("mission.mcl", p.clone()));
    insta::assert_json_snapshot!("prepare_rename", prep);
    let mut params = lsp.at("mission.mcl", p);
    params["newName"] = json!("MoveTo");
    let edit = lsp.request("textDocument/rename", params.clone());
    insta::assert_json_snapshot!("rename_task", lsp.stable(edit));
    // Keywords and non-identifiers are refused.
    let (_, k) = marker(&MISSION.replace("parallel {", "para$0llel {"));
    let r = lsp.request_full("textDocument/prepareRename", lsp.at("mission.mcl", k));
    assert_eq!(r["error"]["message"], "keywords cannot be renamed", "{r}");
    params["newName"] = json!("not");
    let r = lsp.request_full("textDocument/rename", params);
    assert_eq!(r["error"]["message"], "`not` is a keyword", "{r}");
    assert_eq!(lsp.shutdown(), 0);
}

#[test]
fn completion_signature_help_and_edits_in_order() {
    let text = "import \"vehicle.mcl\";\n\nmission {\n    Void() ;\n    \n}\n";
    let root = workspace("completion", &[("vehicle.mcl", VEHICLE), ("mission.mcl", text)]);
    let mut lsp = Lsp::start(&root);
    lsp.initialize(client_caps());
    lsp.open("mission.mcl", text);
    // Type `Go` and ask at once: the request must see the edit.
    let p = json!({"line": 4, "character": 4});
    lsp.change("mission.mcl", 2, json!([{"range": {"start": p, "end": p}, "text": "Go"}]));
    let mut params = lsp.at("mission.mcl", json!({"line": 4, "character": 6}));
    params["context"] = json!({"triggerKind": 1});
    let items = lsp.request("textDocument/completion", params);
    let goto = items.as_array().unwrap().iter().find(|i| i["label"] == "Goto").expect("Goto offered").clone();
    insta::assert_json_snapshot!("completion_goto", goto);
    let labels: Vec<&str> = items.as_array().unwrap().iter().map(|i| i["label"].as_str().unwrap()).collect();
    assert!(labels.contains(&"while") && labels.contains(&"Depth"), "{labels:?}");

    // Finish the call and ask for the signature inside it.
    let p = json!({"line": 4, "character": 6});
    lsp.change("mission.mcl", 3, json!([{"range": {"start": p, "end": p}, "text": "to( [1, 2], "}]));
    let sig = lsp.request("textDocument/signatureHelp", lsp.at("mission.mcl", json!({"line": 4, "character": 18})));
    assert_eq!(sig["signatures"][0]["label"], "Goto( way-point )");
    assert_eq!(sig["activeParameter"], 1);
    assert_eq!(lsp.shutdown(), 0);
}

#[test]
fn other_features() {
    let text = MISSION.replace("Void() : wait", "Voyd() : wait");
    let root = workspace("features", &[("vehicle.mcl", VEHICLE), ("mission.mcl", &text)]);
    let mut lsp = Lsp::start(&root);
    lsp.initialize(client_caps());
    lsp.open("mission.mcl", &text);
    let d = lsp.diagnostics("mission.mcl", Some(1));
    let diag = d["diagnostics"][0].clone();
    assert_eq!(diag["code"], "E0101");
    let uri = lsp.uri("mission.mcl");

    let actions = lsp.request(
        "textDocument/codeAction",
        json!({"textDocument": {"uri": uri}, "range": diag["range"], "context": {"diagnostics": [diag]}}),
    );
    let titles: Vec<&str> = actions.as_array().unwrap().iter().map(|a| a["title"].as_str().unwrap()).collect();
    assert_eq!(titles, ["Replace with `Void`", "Create task `Voyd`"]);
    insta::assert_json_snapshot!("code_action_replace", lsp.stable(actions[0].clone()));

    let symbols = lsp.request("textDocument/documentSymbol", json!({"textDocument": {"uri": uri}}));
    let names: Vec<&str> = symbols.as_array().unwrap().iter().map(|s| s["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["import \"vehicle.mcl\"", "auv", "asc", "constraints"]);

    let ws = lsp.request("workspace/symbol", json!({"query": "Depth"}));
    let names: Vec<&str> = ws.as_array().unwrap().iter().map(|s| s["name"].as_str().unwrap()).collect();
    assert_eq!(names[0], "Depth", "{names:?}");

    let tokens = lsp.request("textDocument/semanticTokens/full", json!({"textDocument": {"uri": uri}}));
    let data = tokens["data"].as_array().unwrap();
    assert_eq!(data.len() % 5, 0);
    assert!(data.len() / 5 >= 30, "{} tokens", data.len() / 5);

    let folds = lsp.request("textDocument/foldingRange", json!({"textDocument": {"uri": uri}}));
    assert!(folds.as_array().unwrap().len() >= 4, "{folds}");

    let hints = lsp.request(
        "textDocument/inlayHint",
        json!({"textDocument": {"uri": uri}, "range": {"start": {"line": 0, "character": 0}, "end": {"line": 30, "character": 0}}}),
    );
    let labels: Vec<&str> = hints.as_array().unwrap().iter().map(|h| h["label"].as_str().unwrap()).collect();
    assert_eq!(labels, ["depth:", "mode:", "depth:", "mode:", "way-point:", "way-point:"]);

    let hl = lsp.request("textDocument/documentHighlight", lsp.at("mission.mcl", pos(&text, "Goto( [0", 1)));
    assert_eq!(hl.as_array().unwrap().len(), 2, "{hl}");
    assert_eq!(lsp.shutdown(), 0);
}

/// Applies LSP text edits (UTF-16 positions) to a text.
fn apply_edits(text: &str, edits: &[Value]) -> String {
    let idx = mcl_syntax::LineIndex::new(text);
    let off = |p: &Value| {
        idx.offset_of_utf16(text, p["line"].as_u64().unwrap() as u32, p["character"].as_u64().unwrap() as u32)
    };
    let mut spans: Vec<(usize, usize, &str)> = edits
        .iter()
        .map(|e| (off(&e["range"]["start"]), off(&e["range"]["end"]), e["newText"].as_str().unwrap()))
        .collect();
    spans.sort_by_key(|s| std::cmp::Reverse((s.0, s.1)));
    let mut out = text.to_string();
    for (s, e, t) in spans {
        out.replace_range(s..e, t);
    }
    out
}

#[test]
fn formatting_the_whole_document() {
    let text = "import \"vehicle.mcl\";\nmission : auv {\n  Depth( 15,\"achieve\" ) : dive ;Goto([24,12])\n}\n";
    let root = workspace("formatting", &[("vehicle.mcl", VEHICLE), ("mission.mcl", text)]);
    let mut lsp = Lsp::start(&root);
    lsp.initialize(client_caps());
    lsp.open("mission.mcl", text);
    let uri = lsp.uri("mission.mcl");
    let params = json!({"textDocument": {"uri": uri}, "options": {"tabSize": 4, "insertSpaces": true}});
    let edits = lsp.request("textDocument/formatting", params.clone());
    let formatted = apply_edits(text, edits.as_array().unwrap());
    insta::assert_snapshot!("formatted", formatted);
    assert_eq!(formatted, mcl_syntax::format::format(text).unwrap());
    // Formatting the result changes nothing.
    lsp.change("mission.mcl", 2, json!([{"text": formatted}]));
    assert_eq!(lsp.request("textDocument/formatting", params.clone()), json!([]));
    // A text with syntax errors is left alone.
    lsp.change("mission.mcl", 3, json!([{"text": "mission { Void( }"}]));
    assert_eq!(lsp.request("textDocument/formatting", params), Value::Null);
    assert_eq!(lsp.shutdown(), 0);
}

#[test]
fn editing_the_vehicle_republishes_its_importers() {
    let root = workspace("importers", &[("vehicle.mcl", VEHICLE), ("mission.mcl", MISSION)]);
    let mut lsp = Lsp::start(&root);
    lsp.initialize(client_caps());
    lsp.open("mission.mcl", MISSION);
    assert_eq!(lsp.diagnostics("mission.mcl", Some(1))["diagnostics"], json!([]));
    lsp.open("vehicle.mcl", VEHICLE);
    lsp.diagnostics("vehicle.mcl", Some(1));
    // Rename the task `Void` in the vehicle only: the mission's call breaks.
    let p = pos(VEHICLE, "Void(): Instant", 0);
    let e = pos(VEHICLE, "Void(): Instant", 4);
    lsp.change("vehicle.mcl", 2, json!([{"range": {"start": p, "end": e}, "text": "Nothing"}]));
    let d = lsp.wait_for("textDocument/publishDiagnostics", |p| {
        p["uri"].as_str().unwrap().ends_with("/mission.mcl")
            && p["diagnostics"].as_array().is_some_and(|d| d.iter().any(|x| x["code"] == "E0101"))
    });
    assert_eq!(d["version"], 1, "the mission's own version: {d}");
    assert_eq!(lsp.shutdown(), 0);
}

#[test]
fn a_vehicle_changed_on_disk_is_reloaded() {
    let root = workspace("watched", &[("vehicle.mcl", VEHICLE), ("mission.mcl", MISSION)]);
    let mut lsp = Lsp::start(&root);
    lsp.initialize(client_caps());
    // The server asks to watch MCL and PNML files.
    let reg = lsp.wait_for("client/registerCapability", |_| true);
    assert_eq!(reg["registrations"][0]["method"], "workspace/didChangeWatchedFiles");
    lsp.open("mission.mcl", MISSION);
    assert_eq!(lsp.diagnostics("mission.mcl", Some(1))["diagnostics"], json!([]));
    std::fs::write(root.join("vehicle.mcl"), VEHICLE.replace("Void(): Instant", "Nothing(): Instant")).unwrap();
    let uri = lsp.uri("vehicle.mcl");
    lsp.notify("workspace/didChangeWatchedFiles", json!({"changes": [{"uri": uri, "type": 2}]}));
    let d = lsp.wait_for("textDocument/publishDiagnostics", |p| {
        p["uri"].as_str().unwrap().ends_with("/mission.mcl")
            && p["diagnostics"].as_array().is_some_and(|d| !d.is_empty())
    });
    assert_eq!(d["diagnostics"][0]["code"], "E0101", "{d}");
    assert_eq!(lsp.shutdown(), 0);
}

#[test]
fn exit_without_shutdown_is_status_1() {
    let root = workspace("exit", &[]);
    let mut lsp = Lsp::start(&root);
    lsp.initialize(client_caps());
    lsp.notify("exit", Value::Null);
    let deadline = Instant::now() + TIMEOUT;
    loop {
        if let Some(s) = lsp.child.try_wait().unwrap() {
            assert_eq!(s.code(), Some(1));
            break;
        }
        assert!(Instant::now() < deadline, "the server did not exit");
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn pull_diagnostics_when_the_client_supports_them() {
    let broken = MISSION.replace("Goto( [0, 0] )", "Goto( 0, 0 )");
    let root = workspace("pull", &[("vehicle.mcl", VEHICLE), ("mission.mcl", &broken)]);
    let mut lsp = Lsp::start(&root);
    let mut caps = client_caps();
    caps["textDocument"]["diagnostic"] = json!({"dynamicRegistration": false, "relatedDocumentSupport": false});
    let init = lsp.initialize(caps);
    assert_eq!(init["capabilities"]["diagnosticProvider"]["interFileDependencies"], true);
    lsp.open("mission.mcl", &broken);
    let uri = lsp.uri("mission.mcl");
    let r = lsp.request("textDocument/diagnostic", json!({"textDocument": {"uri": uri}}));
    assert_eq!(r["kind"], "full");
    assert_eq!(r["items"][0]["code"], "E0201", "{r}");
    assert_eq!(lsp.shutdown(), 0);
}

/// A small deterministic generator (no dependency needed).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n.max(1)
    }
}

#[test]
fn random_edits_and_malformed_requests_never_kill_the_server() {
    let root = workspace("fuzz", &[("vehicle.mcl", VEHICLE), ("mission.mcl", MISSION)]);
    let mut lsp = Lsp::start(&root);
    lsp.initialize(client_caps());
    lsp.open("mission.mcl", MISSION);
    let uri = lsp.uri("mission.mcl");
    // Another seed: MCL_LSP_FUZZ_SEED=n.
    let seed = std::env::var("MCL_LSP_FUZZ_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(0x5eed_1234_abcd);
    let mut rng = Rng(seed | 1);
    let pieces = [
        "{", "}", "(", ")", "[", "]", ";", ":", ",", "->", "→", "é", "𝄞", "\n", " ", "Goto", "mission", "tasks {",
        "/*", "*/", "//", "\"", "0", "-1.5", "a: ", "e: ", "parallel", "and", "or",
    ];
    let methods = [
        "textDocument/hover",
        "textDocument/definition",
        "textDocument/references",
        "textDocument/completion",
        "textDocument/signatureHelp",
        "textDocument/prepareRename",
        "textDocument/documentHighlight",
    ];
    let mut version = 1;
    let started = Instant::now();
    for step in 0..1500 {
        if started.elapsed() > Duration::from_secs(90) {
            break;
        }
        if step % 200 == 199 {
            // Close and reopen the document.
            lsp.notify("textDocument/didClose", json!({"textDocument": {"uri": uri}}));
            version += 1;
            let reopened =
                json!({"textDocument": {"uri": uri, "languageId": "mcl", "version": version, "text": MISSION}});
            lsp.notify("textDocument/didOpen", reopened);
            continue;
        }
        match rng.below(10) {
            0..=4 => {
                // An incremental edit at a random place (possibly past the end).
                version += 1;
                let (l1, c1) = (rng.below(25), rng.below(40));
                let (l2, c2) = if rng.below(3) == 0 { (l1 + rng.below(3), rng.below(60)) } else { (l1, c1) };
                let text = pieces[rng.below(pieces.len() as u64) as usize];
                lsp.change(
                    "mission.mcl",
                    version,
                    json!([{"range": {"start": {"line": l1, "character": c1}, "end": {"line": l2, "character": c2}}, "text": text}]),
                );
            }
            5..=7 => {
                let m = methods[rng.below(methods.len() as u64) as usize];
                let mut params = json!({"textDocument": {"uri": uri}, "position": {"line": rng.below(30), "character": rng.below(50)}});
                if m == "textDocument/references" {
                    params["context"] = json!({"includeDeclaration": true});
                }
                let r = lsp.request_full(m, params);
                assert!(r.get("result").is_some() || r.get("error").is_some(), "{r}");
                assert_ne!(r["error"]["code"], -32603, "a feature failed: {r}");
            }
            8 => {
                let uri = uri.clone();
                let whole = [
                    ("textDocument/semanticTokens/full", json!({"textDocument": {"uri": uri}})),
                    ("textDocument/documentSymbol", json!({"textDocument": {"uri": uri}})),
                    ("textDocument/foldingRange", json!({"textDocument": {"uri": uri}})),
                    (
                        "textDocument/codeAction",
                        json!({"textDocument": {"uri": uri}, "range": {"start": {"line": 0, "character": 0}, "end": {"line": 99, "character": 0}}, "context": {"diagnostics": []}}),
                    ),
                    (
                        "textDocument/inlayHint",
                        json!({"textDocument": {"uri": uri}, "range": {"start": {"line": 0, "character": 0}, "end": {"line": 99, "character": 0}}}),
                    ),
                ];
                let (m, p) = whole[rng.below(whole.len() as u64) as usize].clone();
                let r = lsp.request_full(m, p);
                assert!(r.get("result").is_some() || r.get("error").is_some(), "{r}");
                assert_ne!(r["error"]["code"], -32603, "a feature failed: {r}");
            }
            _ => {
                // Malformed: wrong params, unknown documents and methods, broken JSON.
                match step % 5 {
                    0 => {
                        let r = lsp.request_full("textDocument/hover", json!({"nonsense": true}));
                        assert!(r.get("error").is_some(), "{r}");
                    }
                    1 => {
                        let r = lsp.request_full(
                            "textDocument/hover",
                            lsp.at("nowhere.mcl", json!({"line": 3, "character": 2})),
                        );
                        assert!(r.get("result").is_some() || r.get("error").is_some(), "{r}");
                        assert_ne!(r["error"]["code"], -32603, "a feature failed: {r}");
                    }
                    2 => {
                        let r = lsp.request_full("mcl/unknownMethod", json!([1, 2]));
                        assert_eq!(r["error"]["code"], -32601, "{r}");
                    }
                    3 => lsp.send_raw(b"{ this is not json"),
                    _ => lsp.notify("textDocument/didChange", json!({"textDocument": {"uri": 5}})),
                }
            }
        }
    }
    // Still alive and consistent: the final text has diagnostics for the last version.
    lsp.change("mission.mcl", version + 1, json!([{"text": MISSION}]));
    assert_eq!(lsp.diagnostics("mission.mcl", Some(version + 1))["diagnostics"], json!([]));
    let hover = lsp.request("textDocument/hover", lsp.at("mission.mcl", pos(MISSION, "Goto( [24", 1)));
    assert!(hover["contents"]["value"].as_str().unwrap().contains("Goto( way-point )"));
    assert_eq!(lsp.shutdown(), 0);
}

/// Figure 6.9a of the seed: two orders that wait for each other.
const ORDER_CYCLE: &str = r#"import "vehicle.mcl";

mission : v1 {
    Goto( [1, 1] ) : p2 ;
    Void()
}

mission : v2 {
    Depth( 5, "achieve" ) : p5 ;
    Void()
}

constraints {
    order { v1:p2, v2:p5 }
    order { v2:p5, v1:p2 }
}
"#;

#[test]
fn deadlocking_constraints_are_published_and_cleared_when_fixed() {
    let root = workspace("deadlock", &[("vehicle.mcl", VEHICLE), ("mission.mcl", ORDER_CYCLE)]);
    let mut lsp = Lsp::start(&root);
    lsp.initialize(client_caps());
    lsp.open("mission.mcl", ORDER_CYCLE);
    let d = lsp.diagnostics("mission.mcl", Some(1));
    let diags = d["diagnostics"].as_array().unwrap();
    // The orders conflict by construction (E0408), and deadlock (E0406).
    assert_eq!(diags.len(), 2, "{d}");
    assert_eq!(diags[0]["code"], "E0408", "{d}");
    let e = &diags[1];
    assert_eq!(e["code"], "E0406", "{e}");
    assert_eq!(e["severity"], 1, "an error: {e}");
    assert_eq!(e["range"]["start"], pos(ORDER_CYCLE, "order { v1:p2", 0), "{e}");
    let message = e["message"].as_str().unwrap();
    assert!(message.contains("note: counterexample:") && message.contains("help: "), "{message}");
    // The other order is related information.
    let related = e["relatedInformation"].as_array().unwrap();
    assert!(
        related.iter().any(|r| r["location"]["range"]["start"] == pos(ORDER_CYCLE, "order { v2:p5", 0)
            && r["message"].as_str().unwrap().contains("holds `v1:p2`")),
        "{e}"
    );
    // Remove the second order: the diagnostic goes away.
    lsp.change("mission.mcl", 2, json!([{"text": ORDER_CYCLE.replace("    order { v2:p5, v1:p2 }\n", "")}]));
    assert_eq!(lsp.diagnostics("mission.mcl", Some(2))["diagnostics"], json!([]));
    assert_eq!(lsp.shutdown(), 0);
}
