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
    let r = lsp.request_full("textDocument/rename", params.clone());
    assert_eq!(r["error"]["message"], "`not` is a keyword", "{r}");
    // Not identifiers.
    for bad in ["", "1abc", "a b", "Go(", "x;y", "// c", "\"s\""] {
        params["newName"] = json!(bad);
        let r = lsp.request_full("textDocument/rename", params.clone());
        assert_eq!(r["error"]["message"], format!("`{bad}` is not an identifier"), "{r}");
    }
    // Names taken by a definition of the same kind in scope.
    params["newName"] = json!("Depth");
    let r = lsp.request_full("textDocument/rename", params.clone());
    assert_eq!(r["error"]["message"], "there is already a task named `Depth`", "{r}");
    // Another kind may share the name: an action named `Goto` is no task.
    params["newName"] = json!("enableGoto");
    assert!(lsp.request_full("textDocument/rename", params.clone())["error"].is_null());
    let rename = |lsp: &mut Lsp, at: &str, new: &str| {
        let (_, p) = marker(&MISSION.replacen(at, &format!("{}$0{}", &at[..1], &at[1..]), 1));
        let mut params = lsp.at("mission.mcl", p);
        params["newName"] = json!(new);
        lsp.request_full("textDocument/rename", params)
    };
    let r = rename(&mut lsp, "go\n", "dive");
    assert_eq!(
        r["error"]["message"], "this mission already has a call labelled `dive` (constraints would name both)",
        "{r}"
    );
    assert!(rename(&mut lsp, "go\n", "wait")["error"].is_null(), "a label of another mission");
    let r = rename(&mut lsp, "auv {", "asc");
    assert_eq!(r["error"]["message"], "there is already a mission named `asc`", "{r}");
    let r = rename(&mut lsp, "Void() : wait", "Goto");
    assert_eq!(r["error"]["message"], "there is already a task named `Goto`", "{r}");
    // Renaming to the same name changes nothing and is no collision.
    assert!(rename(&mut lsp, "auv {", "auv")["error"].is_null());
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

/// A ROS 2 bridge file for `VEHICLE` with three errors: a field the
/// message type lacks (line 4), a parameter the command lacks (line 7), a
/// primitive the vehicle lacks (line 9).
const BAD_BRIDGE: &str = r#"node = "mcl_player"

[primitives.GotoPrimitive]
enable = { publish = "/goto", type = "geometry_msgs/msg/Point", fields = { x = "$way-point[0]", w = 1.0 } }

[primitives.DepthPrimitive]
enable = { publish = "/depth", type = "std_msgs/msg/Float64", fields = { data = "$speed" } }

[primitives.SonarPrimitive]
enable = { publish = "/sonar", type = "std_msgs/msg/Bool" }
"#;

const GOOD_BRIDGE: &str = r#"node = "mcl_player"

[primitives.GotoPrimitive]
enable = { publish = "/goto", type = "geometry_msgs/msg/Point", fields = { x = "$way-point[0]", y = 1.0 } }

[primitives.DepthPrimitive]
enable = { publish = "/depth", type = "std_msgs/msg/Float64", fields = { data = "$depth" } }
"#;

#[test]
fn a_configured_ros2_bridge_is_checked_against_the_open_vehicle() {
    let root =
        workspace("ros2-bridge", &[("vehicle.mcl", VEHICLE), ("mission.mcl", MISSION), ("BRIDGE.toml", BAD_BRIDGE)]);
    let mut lsp = Lsp::start(&root);
    let r = uri_of(&root);
    lsp.request(
        "initialize",
        json!({"processId": null, "rootUri": r, "capabilities": client_caps(),
               "workspaceFolders": [{"uri": r, "name": "ws"}],
               "initializationOptions": {"ros2Bridge": "BRIDGE.toml"}}),
    );
    lsp.notify("initialized", json!({}));
    let bridge = lsp.uri("BRIDGE.toml");
    let count = |n: usize| {
        let bridge = bridge.clone();
        move |p: &Value| p["uri"] == bridge.as_str() && p["diagnostics"].as_array().is_some_and(|d| d.len() == n)
    };
    // With an MCL document open, the bridge's errors against its vehicle,
    // each at its line, on the bridge file's URI.
    lsp.open("mission.mcl", MISSION);
    let d = lsp.wait_for("textDocument/publishDiagnostics", count(3));
    let found: Vec<(i64, String)> = d["diagnostics"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| (d["range"]["start"]["line"].as_i64().unwrap(), d["message"].as_str().unwrap().to_string()))
        .collect();
    let at = |line: i64, needle: &str| {
        assert!(found.iter().any(|(l, m)| *l == line && m.contains(needle)), "`{needle}` on line {line}: {found:?}")
    };
    at(3, "`w`");
    at(6, "has no parameter `speed`");
    at(8, "has no primitive `SonarPrimitive`");
    assert!(d["diagnostics"].as_array().unwrap().iter().all(|d| d["code"] == "ros2" && d["severity"] == 1), "{d}");
    // Fixed on disk: the errors go.
    std::fs::write(root.join("BRIDGE.toml"), GOOD_BRIDGE).unwrap();
    lsp.notify("workspace/didChangeWatchedFiles", json!({"changes": [{"uri": bridge, "type": 2}]}));
    lsp.wait_for("textDocument/publishDiagnostics", count(0));
    // The vehicle loses a parameter in the editor: the bridge that uses it
    // is wrong again.
    lsp.open("vehicle.mcl", VEHICLE);
    let changed = VEHICLE.replace("GotoPrimitive( c: enable, v: way-point )", "GotoPrimitive( c: enable )");
    lsp.change("vehicle.mcl", 2, json!([{"text": changed}]));
    let d = lsp.wait_for("textDocument/publishDiagnostics", count(1));
    assert_eq!(d["diagnostics"][0]["range"]["start"]["line"], 3, "{d}");
    assert!(d["diagnostics"][0]["message"].as_str().unwrap().contains("way-point"), "{d}");
    // The bridge file edited in the editor: its text wins over the disk's,
    // and it is never diagnosed as MCL.
    let edited = format!(
        "{GOOD_BRIDGE}\n[primitives.SonarPrimitive]\nenable = {{ publish = \"/s\", type = \"std_msgs/msg/Bool\" }}\n"
    );
    lsp.notify(
        "textDocument/didOpen",
        json!({"textDocument": {"uri": bridge, "languageId": "toml", "version": 1, "text": edited}}),
    );
    let d = lsp.wait_for("textDocument/publishDiagnostics", count(2));
    assert_eq!(d["version"], 1, "{d}");
    assert!(d["diagnostics"].as_array().unwrap().iter().all(|d| d["code"] == "ros2"), "{d}");
    let stray: Vec<&Value> = lsp
        .stash
        .iter()
        .filter(|m| m["method"] == "textDocument/publishDiagnostics" && m["params"]["uri"] == bridge.as_str())
        .flat_map(|m| m["params"]["diagnostics"].as_array().into_iter().flatten())
        .filter(|d| d["code"] != "ros2")
        .collect();
    assert!(stray.is_empty(), "the bridge file was diagnosed as MCL: {stray:?}");
    assert_eq!(lsp.shutdown(), 0);
}

/// A FIFO and a device imported by an open document: errors at the imports,
/// and the server never blocks on them (the other document still gets its
/// diagnostics).
#[cfg(unix)]
#[test]
fn imports_of_fifos_and_devices_are_errors_and_never_block() {
    let mission = "import \"pipe.mcl\";\nimport \"/dev/zero\";\nmission { Void() }\n";
    let root = workspace("special", &[("vehicle.mcl", VEHICLE), ("m.mcl", mission), ("mission.mcl", MISSION)]);
    let made = std::process::Command::new("mkfifo").arg(root.join("pipe.mcl")).status().unwrap();
    assert!(made.success());
    let mut lsp = Lsp::start(&root);
    lsp.initialize(client_caps());
    lsp.open("m.mcl", mission);
    let d = lsp.diagnostics("m.mcl", Some(1));
    let messages: Vec<&str> = d["diagnostics"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|x| x["code"] == "E0501")
        .map(|x| x["message"].as_str().unwrap())
        .collect();
    assert_eq!(messages.len(), 2, "{d}");
    assert!(messages[0].contains("FIFO") && messages[1].contains("character device"), "{messages:?}");
    lsp.open("mission.mcl", MISSION);
    assert_eq!(lsp.diagnostics("mission.mcl", Some(1))["diagnostics"], json!([]));
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

/// Writes `raw` bytes, then a request framed by `header` (`{len}` is
/// replaced by the body's length); returns its answer.
fn raw_request(lsp: &mut Lsp, raw: &[u8], header: &str, method: &str, params: Value) -> Value {
    lsp.next_id += 1;
    let id = lsp.next_id;
    let body = serde_json::to_vec(&json!({"jsonrpc": "2.0", "id": id, "method": method, "params": params})).unwrap();
    let _ = lsp.stdin.write_all(raw);
    let _ = lsp.stdin.write_all(header.replace("{len}", &body.len().to_string()).as_bytes());
    let _ = lsp.stdin.write_all(&body);
    let _ = lsp.stdin.flush();
    let deadline = Instant::now() + TIMEOUT;
    loop {
        let m = lsp
            .recv(deadline)
            .unwrap_or_else(|| panic!("no answer after {:?} / {header:?}", String::from_utf8_lossy(raw)));
        if m.get("id") == Some(&json!(id)) && m.get("method").is_none() {
            return m;
        }
        lsp.stash.push_back(m);
    }
}

#[test]
fn malformed_framing_is_skipped_and_the_server_keeps_serving() {
    let root = workspace("framing", &[("vehicle.mcl", VEHICLE), ("mission.mcl", MISSION)]);
    let mut lsp = Lsp::start(&root);
    lsp.initialize(client_caps());
    lsp.open("mission.mcl", MISSION);
    let at = lsp.at("mission.mcl", pos(MISSION, "Goto( [24", 1));
    let ok = "Content-Length: {len}\r\n\r\n";
    let cases: Vec<(&[u8], &str)> = vec![
        // Garbage between messages, and a header glued to it.
        (b"garbage\r\n\x00\x01\xff", ok),
        (b"}{]\r\n\r\n", ok),
        // A body that is not JSON, one that is JSON but not JSON-RPC, an empty one.
        (b"Content-Length: 18\r\n\r\n{ this is not json", ok),
        (b"Content-Length: 8\r\n\r\n[1, 2, 3]", ok),
        (b"Content-Length: 0\r\n\r\n", ok),
        // Headers without a usable length.
        (b"Content-Type: text/plain\r\n\r\n", ok),
        (b"", "Content-Length: twelve\r\n\r\n"),
        (b"", "Content-Length: -1\r\n\r\n"),
        (b"", "Content-Length:\r\n\r\n"),
        // Lengths that do not match the body: too small, too large, huge.
        (b"", "Content-Length: 10\r\n\r\n"),
        (b"", "Content-Length: 100000\r\n\r\n"),
        (b"", "Content-Length: 99999999999999999999\r\n\r\n"),
        (b"", "Content-Length: 4000000000\r\n\r\n"),
        // Lower case, no carriage returns, other headers.
        (b"", "content-length: {len}\n\n"),
        (b"", "Content-Length: {len}\r\nContent-Type: application/vscode-jsonrpc; charset=utf-8\r\n\r\n"),
    ];
    for (raw, header) in cases {
        let r = raw_request(&mut lsp, raw, header, "textDocument/hover", at.clone());
        let shown = r["result"]["contents"]["value"].as_str().unwrap_or_default().to_string();
        assert!(shown.contains("Goto( way-point )"), "after {:?} / {header:?}: {r}", String::from_utf8_lossy(raw));
    }
    // Edits sent after all that still apply, in order.
    let p = pos(MISSION, "Void() : wait", 0);
    lsp.change("mission.mcl", 2, json!([{"range": {"start": p, "end": p}, "text": "Nope() ; "}]));
    let d = lsp.diagnostics("mission.mcl", Some(2));
    assert_eq!(d["diagnostics"][0]["code"], "E0101", "{d}");
    assert_eq!(lsp.shutdown(), 0);
}

/// The LSP position of a byte offset, counted independently of the server:
/// lines end at `\n`, `\r\n` or a lone `\r`; columns are UTF-16 units.
fn lsp_position(text: &str, offset: usize) -> Value {
    let (mut line, mut col) = (0, 0);
    let mut chars = text[..offset].chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\r' if chars.peek() == Some(&'\n') => {}
            '\n' | '\r' => {
                line += 1;
                col = 0;
            }
            c => col += c.len_utf16(),
        }
    }
    json!({"line": line, "character": col})
}

const ASTRAL: &str = "import \"vehicle.mcl\";
// \u{1D11E} A mission with astral characters: \u{1F600}\u{1F600}
mission : auv {
    /* \u{1F600} */ Depth( 15, \"achieve\" ) : dive ;
    parallel {
        Depth( 15, \"keep\" )
    } or {
        /* \u{1D11E}\u{1D11E} */ Goto( [24, 12] ) : go
    }
}

mission : asc {
    /* \u{1F600} */ Void() : wait ;
    /* \u{1D11E} */ Goto( 0, 0 )
}

constraints {
    mutex { auv:go, asc:wait } = 1
}
";

#[test]
fn line_ends_and_astral_characters_map_positions() {
    for (name, eol) in [("crlf", "\r\n"), ("cr", "\r"), ("lf", "\n")] {
        let text = ASTRAL.replace('\n', eol);
        let root = workspace(&format!("line-ends-{name}"), &[("vehicle.mcl", VEHICLE), ("mission.mcl", &text)]);
        let mut lsp = Lsp::start(&root);
        lsp.initialize(client_caps());
        lsp.open("mission.mcl", &text);
        // The diagnostic is where the client shows the text.
        let d = lsp.diagnostics("mission.mcl", Some(1));
        let e = &d["diagnostics"][0];
        assert_eq!(e["code"], "E0201", "{name}: {d}");
        let args = text.find("( 0, 0 )").unwrap();
        assert_eq!(e["range"]["start"], lsp_position(&text, args), "{name}: {e}");
        assert_eq!(e["range"]["end"], lsp_position(&text, args + "( 0, 0 )".len()), "{name}: {e}");
        // Hover after astral characters on the same line.
        let goto = text.find("Goto( [24").unwrap() + 2;
        let hover = lsp.request("textDocument/hover", lsp.at("mission.mcl", lsp_position(&text, goto)));
        assert!(hover["contents"]["value"].as_str().unwrap_or("").contains("Goto( way-point )"), "{name}: {hover}");
        // Definition of a label used in a constraint.
        let used = text.find("asc:wait").unwrap() + 5;
        let def = lsp.request("textDocument/definition", lsp.at("mission.mcl", lsp_position(&text, used)));
        let label = text.find("wait ;").unwrap();
        assert_eq!(def["range"]["start"], lsp_position(&text, label), "{name}: {def}");
        // An edit at a column past the end of a line goes before its line end.
        let line = lsp_position(&text, label)["line"].clone();
        let past = json!({"line": line, "character": 999});
        lsp.change("mission.mcl", 2, json!([{"range": {"start": past, "end": past}, "text": "Nope() ;"}]));
        let edited = text.replacen("wait ;", "wait ;Nope() ;", 1);
        let d = lsp.diagnostics("mission.mcl", Some(2));
        let e = d["diagnostics"].as_array().unwrap().iter().find(|x| x["code"] == "E0101").expect("E0101").clone();
        let nope = edited.find("Nope()").unwrap();
        assert_eq!(e["range"]["start"], lsp_position(&edited, nope), "{name}: {d}");
        // A range inside an astral character, and one past the end of the text.
        let inside = json!({"line": 1, "character": 4});
        lsp.change("mission.mcl", 3, json!([{"range": {"start": inside, "end": inside}, "text": "x"}]));
        let end = json!({"line": 999, "character": 3});
        lsp.change("mission.mcl", 4, json!([{"range": {"start": end, "end": end}, "text": "mission { Void() }"}]));
        let d = lsp.diagnostics("mission.mcl", Some(4));
        let e = d["diagnostics"].as_array().unwrap().iter().find(|x| x["code"] == "E0101").expect("E0101").clone();
        let mut final_text = edited.clone();
        final_text.insert(final_text.find('\u{1D11E}').unwrap() + 4, 'x');
        final_text.push_str("mission { Void() }");
        assert_eq!(e["range"]["start"], lsp_position(&final_text, final_text.find("Nope()").unwrap()), "{name}: {d}");
        // Formatting keeps the document's line ends.
        let params =
            json!({"textDocument": {"uri": lsp.uri("mission.mcl")}, "options": {"tabSize": 4, "insertSpaces": true}});
        let edits = lsp.request("textDocument/formatting", params);
        for e in edits.as_array().unwrap_or_else(|| panic!("{name}: not formatted: {edits}")) {
            let t = e["newText"].as_str().unwrap();
            match name {
                "crlf" => assert_eq!(t.matches('\n').count(), t.matches("\r\n").count(), "{t:?}"),
                "cr" => assert!(!t.contains('\n'), "{t:?}"),
                _ => assert!(!t.contains('\r'), "{t:?}"),
            }
        }
        assert_eq!(lsp.shutdown(), 0);
    }
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
    // A fixed number of steps: the sequence depends only on the seed.
    for step in 0..1500 {
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

/// On E0406 the server offers to write a scenario that replays the
/// counterexample (`mcl_coord::replay`): an edit creating
/// `mission.counterexample.toml` next to the source, which `mcl run` replays
/// to the deadlock.
#[test]
fn a_deadlock_offers_a_counterexample_scenario() {
    let root = workspace("deadlock-scenario", &[("vehicle.mcl", VEHICLE), ("mission.mcl", ORDER_CYCLE)]);
    let mut lsp = Lsp::start(&root);
    lsp.initialize(client_caps());
    lsp.open("mission.mcl", ORDER_CYCLE);
    let d = lsp.diagnostics("mission.mcl", Some(1));
    let e = d["diagnostics"][1].clone();
    assert_eq!(e["code"], "E0406", "{d}");
    let uri = lsp.uri("mission.mcl");
    let actions = lsp.request(
        "textDocument/codeAction",
        json!({"textDocument": {"uri": uri}, "range": e["range"], "context": {"diagnostics": [e]}}),
    );
    let action = actions
        .as_array()
        .unwrap()
        .iter()
        .find(|a| a["title"] == "Write a dry run of this counterexample to mission.counterexample.toml")
        .unwrap_or_else(|| panic!("{actions}"))
        .clone();
    assert_eq!(action["diagnostics"][0]["code"], "E0406", "{action}");
    let ops = action["edit"]["documentChanges"].as_array().unwrap();
    let target = uri_of(&root.join("mission.counterexample.toml"));
    assert_eq!(ops[0]["kind"], "create", "{action}");
    assert_eq!(ops[0]["uri"], target.as_str(), "{action}");
    assert_eq!(ops[0]["options"]["overwrite"], true, "{action}");
    assert_eq!(ops[1]["textDocument"]["uri"], target.as_str(), "{action}");
    let text = ops[1]["edits"][0]["newText"].as_str().unwrap();
    assert!(text.contains("[counterexample]\ncode = \"E0406\""), "{text}");
    // Nothing is offered away from the deadlock.
    let elsewhere = lsp.request(
        "textDocument/codeAction",
        json!({"textDocument": {"uri": uri}, "range": {"start": pos(ORDER_CYCLE, "Void()", 0), "end": pos(ORDER_CYCLE, "Void()", 0)},
               "context": {"diagnostics": []}}),
    );
    assert_eq!(elsewhere, json!([]), "{elsewhere}");
    assert_eq!(lsp.shutdown(), 0);
    // The file the edit makes replays the deadlock.
    let scenario = root.join("mission.counterexample.toml");
    std::fs::write(&scenario, text).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_mcl"))
        .args(["run", "--mock", "--virtual-time", "-q", "mission.mcl", "--scenario"])
        .arg(&scenario)
        .current_dir(&root)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(err.contains("reproduced (`v1` stuck, `v2` stuck"), "{err}");
}

#[test]
fn a_valid_coordination_verdict_stays_through_edits_elsewhere() {
    let root = workspace("deadlock-kept", &[("vehicle.mcl", VEHICLE), ("mission.mcl", ORDER_CYCLE)]);
    let mut lsp = Lsp::start(&root);
    lsp.initialize(client_caps());
    lsp.open("mission.mcl", ORDER_CYCLE);
    let uri = lsp.uri("mission.mcl");
    let has_e0406 = |p: &Value| p["diagnostics"].as_array().is_some_and(|d| d.iter().any(|x| x["code"] == "E0406"));
    lsp.wait_for("textDocument/publishDiagnostics", |p| p["uri"] == uri.as_str() && has_e0406(p));
    // Every publication for `version` within a while.
    let publications = |lsp: &mut Lsp, version: i64| {
        let first =
            lsp.wait_for("textDocument/publishDiagnostics", |p| p["uri"] == uri.as_str() && p["version"] == version);
        let mut all = vec![first];
        let deadline = Instant::now() + Duration::from_millis(500);
        while let Some(m) = lsp.recv(deadline) {
            if m["method"] == "textDocument/publishDiagnostics" && m["params"]["version"] == version {
                all.push(m["params"].clone());
            }
        }
        all
    };
    // A comment above the missions: every publication for the new version
    // shows the verdict, one line lower.
    let zero = json!({"line": 0, "character": 0});
    lsp.change("mission.mcl", 2, json!([{"range": {"start": zero, "end": zero}, "text": "// two orders\n"}]));
    let moved = format!("// two orders\n{ORDER_CYCLE}");
    for p in publications(&mut lsp, 2) {
        assert_eq!(p["diagnostics"][0]["code"], "E0408", "{p}");
        assert_eq!(p["diagnostics"][1]["code"], "E0406", "{p}");
        assert_eq!(p["diagnostics"][0]["range"]["start"], pos(&moved, "order { v1:p2", 0), "{p}");
    }
    // An unused task in the same file changes nothing either.
    let end = lsp_position(&moved, moved.len());
    lsp.change(
        "mission.mcl",
        3,
        json!([{"range": {"start": end, "end": end}, "text": "tasks {\n    _Idle(): Instant { }\n}\n"}]),
    );
    for p in publications(&mut lsp, 3) {
        assert!(has_e0406(&p), "{p}");
    }
    // Removing one order fixes it: the verdict goes away.
    let fixed = moved.replace("    order { v2:p5, v1:p2 }\n", "");
    let fixed = format!("{fixed}tasks {{\n    _Idle(): Instant {{ }}\n}}\n");
    lsp.change("mission.mcl", 4, json!([{"text": fixed}]));
    assert_eq!(lsp.diagnostics("mission.mcl", Some(4))["diagnostics"], json!([]));
    assert_eq!(lsp.shutdown(), 0);
}

#[test]
fn pulled_diagnostics_refresh_for_the_verdict_and_cancel_when_stale() {
    let big = mcl_syntax::gen::program(400, 7);
    let root = workspace("pull-refresh", &[("vehicle.mcl", VEHICLE), ("mission.mcl", ORDER_CYCLE), ("big.mcl", &big)]);
    let mut lsp = Lsp::start(&root);
    let mut caps = client_caps();
    caps["textDocument"]["diagnostic"] = json!({"dynamicRegistration": false});
    caps["workspace"]["diagnostics"] = json!({"refreshSupport": true});
    lsp.initialize(caps);
    lsp.open("mission.mcl", ORDER_CYCLE);
    let uri = lsp.uri("mission.mcl");
    let pull =
        |lsp: &mut Lsp, uri: &str| lsp.request_full("textDocument/diagnostic", json!({"textDocument": {"uri": uri}}));
    // The answer comes without waiting for the deadlock analysis; once it
    // is done the server asks the client to pull again.
    let r = pull(&mut lsp, &uri);
    assert_eq!(r["result"]["kind"], "full", "{r}");
    lsp.wait_for("workspace/diagnostic/refresh", |_| true);
    let r = pull(&mut lsp, &uri);
    assert_eq!(r["result"]["items"][0]["code"], "E0408", "{r}");
    assert_eq!(r["result"]["items"][1]["code"], "E0406", "{r}");
    // An edit elsewhere keeps it, moved.
    let zero = json!({"line": 0, "character": 0});
    lsp.change("mission.mcl", 2, json!([{"range": {"start": zero, "end": zero}, "text": "\n\n"}]));
    let r = pull(&mut lsp, &uri);
    let moved = format!("\n\n{ORDER_CYCLE}");
    assert_eq!(r["result"]["items"][0]["range"]["start"], pos(&moved, "order { v1:p2", 0), "{r}");

    // A pull made stale by edits is cancelled, and the client told to retry.
    lsp.open("big.mcl", &big);
    let big_uri = lsp.uri("big.mcl");
    lsp.next_id += 1;
    let id = lsp.next_id;
    lsp.send(&json!({"jsonrpc": "2.0", "id": id, "method": "textDocument/diagnostic", "params": {"textDocument": {"uri": big_uri}}}));
    let mut version = 1;
    let answer = loop {
        version += 1;
        lsp.change("big.mcl", version, json!([{"range": {"start": zero, "end": zero}, "text": " "}]));
        let deadline = Instant::now() + Duration::from_millis(5);
        let mut got = None;
        while let Some(m) = lsp.recv(deadline) {
            if m.get("id") == Some(&json!(id)) && m.get("method").is_none() {
                got = Some(m);
                break;
            }
            lsp.stash.push_back(m);
        }
        if let Some(m) = got {
            break m;
        }
        assert!(version < 20_000, "no answer");
    };
    assert_eq!(answer["error"]["code"], -32802, "{answer}");
    assert_eq!(answer["error"]["data"]["retriggerRequest"], true, "{answer}");
    // Pulled again once the edits stop, it is answered.
    let r = pull(&mut lsp, &big_uri);
    assert_eq!(r["result"]["kind"], "full", "{r}");
    assert_eq!(lsp.shutdown(), 0);
}

/// Cuts `text` at a character boundary at or before `i`.
fn floor(text: &str, mut i: usize) -> usize {
    i = i.min(text.len());
    while !text.is_char_boundary(i) {
        i -= 1;
    }
    i
}

/// A random mutation of a whole document.
fn mutate(rng: &mut Rng, text: &str, pieces: &[&str]) -> String {
    let mut t = text.to_string();
    for _ in 0..1 + rng.below(4) {
        let a = floor(&t, rng.below(t.len() as u64 + 1) as usize);
        let b = floor(&t, a + rng.below(200) as usize);
        match rng.below(7) {
            0 => t.replace_range(a..b, ""),
            1 => {
                let copy = t[a..b].to_string();
                let c = floor(&t, rng.below(t.len() as u64 + 1) as usize);
                t.insert_str(c, &copy);
            }
            2 => t.insert_str(a, pieces[rng.below(pieces.len() as u64) as usize]),
            3 => t.truncate(a),
            4 => t = t.replace('\n', if rng.below(2) == 0 { "\r\n" } else { "\r" }),
            5 => t.replace_range(a..b, &t[a..b].chars().rev().collect::<String>()),
            _ => {
                let i = t.find(['{', '}', '(', ')', ';']).map_or(0, |i| i + rng.below(3) as usize);
                let i = floor(&t, i);
                t.insert(i, '}');
            }
        }
    }
    t
}

#[test]
fn mutated_examples_and_edit_sequences_never_kill_the_server() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut files: Vec<(String, String)> = std::fs::read_dir(&src)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.path().extension().is_some_and(|x| x == "mcl"))
        .map(|e| (e.file_name().to_string_lossy().into_owned(), std::fs::read_to_string(e.path()).unwrap()))
        .collect();
    files.sort();
    let refs: Vec<(&str, &str)> = files.iter().map(|(n, t)| (n.as_str(), t.as_str())).collect();
    let root = workspace("fuzz-examples", &refs);
    std::fs::create_dir_all(root.join("patterns")).unwrap();
    std::fs::copy(src.join("patterns/sonar.xml"), root.join("patterns/sonar.xml")).unwrap();
    let mut lsp = Lsp::start(&root);
    let mut caps = client_caps();
    if std::env::var("MCL_LSP_FUZZ_PULL").is_ok() {
        caps["textDocument"]["diagnostic"] = json!({});
    }
    lsp.initialize(caps);
    let seed = std::env::var("MCL_LSP_FUZZ_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(0xfa57_c0de_u64);
    let mut rng = Rng(seed | 1);
    let pieces = [
        "{",
        "}",
        "(",
        ")",
        ";",
        "->",
        "→",
        "𝄞",
        "é",
        "\r",
        "\r\n",
        "/*",
        "*/",
        "//",
        "\"",
        "\\",
        "\u{0}",
        "mission",
        "tasks {",
        "parallel {",
        "} or {",
        "monitor {",
        "} condition (",
        ") do {",
        "while (",
        "try {",
        "} catch {",
        "mutex {",
        "order {",
        "sync {",
        "} = 2",
        ":",
        ",",
        "import \"vehicle.mcl\";",
        "import \"nowhere.mcl\";",
        "import \"mission-operators.mcl\";",
    ];
    let methods = [
        "textDocument/hover",
        "textDocument/definition",
        "textDocument/references",
        "textDocument/completion",
        "textDocument/signatureHelp",
        "textDocument/prepareRename",
        "textDocument/rename",
        "textDocument/documentHighlight",
        "textDocument/semanticTokens/full",
        "textDocument/documentSymbol",
        "textDocument/foldingRange",
        "textDocument/formatting",
        "textDocument/codeAction",
        "textDocument/inlayHint",
        "textDocument/diagnostic",
        "workspace/symbol",
    ];
    let mut requests = 0;
    // A fixed number of rounds: the sequence depends only on the seed.
    for round in 0..400 {
        let (name, base) = refs[rng.below(refs.len() as u64) as usize];
        let uri = lsp.uri(name);
        let mut text = mutate(&mut rng, base, &pieces);
        lsp.notify(
            "textDocument/didOpen",
            json!({"textDocument": {"uri": uri, "languageId": "mcl", "version": 1, "text": text}}),
        );
        let mut version = 1;
        for _ in 0..1 + rng.below(6) {
            // An edit sequence: incremental changes (some past the end), or the whole text.
            version += 1;
            if rng.below(4) == 0 {
                text = mutate(&mut rng, &text, &pieces);
                lsp.change(name, version, json!([{"text": text}]));
            } else {
                let n = 1 + rng.below(3);
                let changes: Vec<Value> = (0..n)
                    .map(|_| {
                        let (l, c) = (rng.below(300), rng.below(90));
                        let (l2, c2) = if rng.below(3) == 0 { (l + rng.below(4), rng.below(90)) } else { (l, c) };
                        let t = pieces[rng.below(pieces.len() as u64) as usize];
                        json!({"range": {"start": {"line": l, "character": c}, "end": {"line": l2, "character": c2}}, "text": t})
                    })
                    .collect();
                lsp.change(name, version, json!(changes));
            }
            let m = methods[rng.below(methods.len() as u64) as usize];
            let p = json!({"line": rng.below(300), "character": rng.below(90)});
            let range = json!({"start": {"line": 0, "character": 0}, "end": {"line": rng.below(400), "character": 0}});
            let params = match m {
                "workspace/symbol" => json!({"query": pieces[rng.below(pieces.len() as u64) as usize]}),
                "textDocument/references" => {
                    json!({"textDocument": {"uri": uri}, "position": p, "context": {"includeDeclaration": true}})
                }
                "textDocument/rename" => json!({"textDocument": {"uri": uri}, "position": p, "newName": "Renamed"}),
                "textDocument/formatting" => {
                    json!({"textDocument": {"uri": uri}, "options": {"tabSize": 4, "insertSpaces": true}})
                }
                "textDocument/codeAction" => {
                    json!({"textDocument": {"uri": uri}, "range": range, "context": {"diagnostics": []}})
                }
                "textDocument/inlayHint" => json!({"textDocument": {"uri": uri}, "range": range}),
                "textDocument/semanticTokens/full"
                | "textDocument/documentSymbol"
                | "textDocument/foldingRange"
                | "textDocument/diagnostic" => json!({"textDocument": {"uri": uri}}),
                _ => json!({"textDocument": {"uri": uri}, "position": p}),
            };
            let r = lsp.request_full(m, params);
            requests += 1;
            assert!(r.get("result").is_some() || r.get("error").is_some(), "round {round}: {r}");
            assert_ne!(r["error"]["code"], -32603, "round {round}, {m} failed: {r}");
        }
        lsp.notify("textDocument/didClose", json!({"textDocument": {"uri": uri}}));
    }
    assert!(requests > 0);
    // Alive, and right on a good text.
    lsp.open("extract-5-4.mcl", refs.iter().find(|(n, _)| *n == "extract-5-4.mcl").unwrap().1);
    assert_eq!(lsp.diagnostics("extract-5-4.mcl", Some(1))["diagnostics"], json!([]));
    assert_eq!(lsp.shutdown(), 0);
}
