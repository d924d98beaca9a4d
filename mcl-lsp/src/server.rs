//! The protocol side: tower-lsp-server glue.
//!
//! * Edits (`didOpen`, `didChange`, `didClose`, `didChangeWatchedFiles`)
//!   are taken off the wire by [`Ordered`] in the order they arrive (the
//!   transport calls `Service::call` in order, then runs handlers
//!   concurrently) and applied by one host thread.
//! * Every request first waits until the edits received before it are
//!   applied, then runs on the blocking pool with a database snapshot that
//!   is never held across an `.await`. When a newer edit cancels it, salsa
//!   unwinds with `Cancelled` and the request is answered `ContentModified`.
//! * One analysis thread publishes diagnostics after each batch of edits:
//!   syntax errors first when there are any, then every diagnostic of
//!   `check_file`, each tagged with the document version it was computed on.

use crate::analysis::coordination::{self, Verdict};
use crate::analysis::{self, Analysis};
use crate::host::{Edit, Host, Snapshot};
use mcl_compiler::queries::program;
use std::collections::{HashMap, HashSet};
use std::panic::AssertUnwindSafe;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{mpsc, Arc};
use std::task::{Context, Poll};
use tokio::sync::{mpsc as tmpsc, watch};
use tower_lsp_server::jsonrpc::{Error, ErrorCode, Request, Response, Result};
use tower_lsp_server::ls_types::*;
use tower_lsp_server::{Client, LanguageServer, LspService, Server};

/// What the client said it supports.
#[derive(Default)]
struct Caps {
    snippets: AtomicBool,
    pull_diagnostics: AtomicBool,
    diagnostic_refresh: AtomicBool,
    watch_registration: AtomicBool,
}

/// State shared by the protocol handlers, the host thread and the analysis thread.
struct Shared {
    host: Host,
    caps: Caps,
    /// Sequence number of the last edit taken off the wire.
    enqueued: AtomicU64,
    /// Edits of texts taken off the wire (not the workspace scan).
    text_edits: AtomicU64,
    edits: std::sync::Mutex<mpsc::Sender<(u64, Edit)>>,
    /// `shutdown` was received (the exit status is 0 only then).
    shut_down: AtomicBool,
    /// `exit` was received: stop at once, even with handlers still waiting
    /// for the client (a registration it never answered).
    exit: tokio::sync::Notify,
    /// The last coordination verdict of each file (see
    /// [`analysis::coordination`]), written by the analysis thread.
    verdicts: std::sync::Mutex<HashMap<PathBuf, Verdict>>,
    /// The ROS 2 bridge file the client named, if any ([`analysis::bridge`]).
    bridge: std::sync::Mutex<Option<PathBuf>>,
    /// The first workspace folder: where a relative bridge path starts.
    root: std::sync::Mutex<Option<PathBuf>>,
    /// The URIs that show bridge diagnostics now.
    bridge_shown: std::sync::Mutex<HashSet<String>>,
}

/// Where a file's coordination verdict stands on a snapshot.
enum Coord {
    /// No analysis: no constraints, or errors in the program.
    None,
    /// The last verdict is still valid: its diagnostics, placed in the current text.
    Valid(Vec<mcl_syntax::Diagnostic>),
    /// To be computed; the input's fingerprint.
    Stale(u64),
}

impl Shared {
    fn verdicts(&self) -> std::sync::MutexGuard<'_, HashMap<PathBuf, Verdict>> {
        self.verdicts.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The last verdict of `file`, if it had diagnostics, placed in the
    /// current text without checking that it still holds (cheap: the parse).
    fn carried(&self, a: &Analysis<'_>, file: mcl_compiler::SourceFile) -> Option<Vec<mcl_syntax::Diagnostic>> {
        let last = self.verdicts().get(a.path(file)).filter(|v| !v.diags.is_empty()).cloned()?;
        coordination::place(a, file, &last, &coordination::anchors(a, file))
    }

    /// Whether the last verdict of `file` still holds (compiles its missions).
    fn coord(&self, a: &Analysis<'_>, file: mcl_compiler::SourceFile) -> Coord {
        let Some(fp) = coordination::fingerprint(a, file) else {
            self.verdicts().remove(a.path(file));
            return Coord::None;
        };
        let last = self.verdicts().get(a.path(file)).cloned();
        match last.and_then(|v| coordination::reuse(a, file, &v, fp)) {
            Some(v) => {
                let diags = v.diags.clone();
                self.verdicts().insert(a.path(file).to_path_buf(), v);
                Coord::Valid(diags)
            }
            None => Coord::Stale(fp),
        }
    }

    /// Runs the analysis and keeps its verdict; returns it and whether it
    /// differs from the previous one.
    fn compute_verdict(
        &self,
        a: &Analysis<'_>,
        file: mcl_compiler::SourceFile,
        fingerprint: u64,
    ) -> (Vec<mcl_syntax::Diagnostic>, bool) {
        let v = coordination::compute(a, file, fingerprint);
        let diags = v.diags.clone();
        let old = self.verdicts().insert(a.path(file).to_path_buf(), v);
        let changed = old.is_none_or(|o| o.diags != diags);
        (diags, changed)
    }

    fn enqueue(&self, edit: Edit) {
        if !matches!(edit, Edit::Workspace { .. }) {
            self.text_edits.fetch_add(1, Ordering::SeqCst);
        }
        // Numbered under the lock, so that the queue is in numbering order.
        let tx = self.edits.lock().unwrap_or_else(|e| e.into_inner());
        let seq = self.enqueued.fetch_add(1, Ordering::SeqCst) + 1;
        let _ = tx.send((seq, edit));
    }
}

pub struct Backend {
    client: Client,
    shared: Arc<Shared>,
    applied: watch::Receiver<u64>,
}

/// A lock that survives a panic in another holder.
fn lock<T>(m: &std::sync::Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

fn content_modified() -> Error {
    Error::new(ErrorCode::ContentModified)
}

/// `ServerCancelled` (-32802) asking the client to pull again, as the
/// protocol says a server cancels a stale `textDocument/diagnostic`.
fn server_cancelled() -> Error {
    Error {
        code: ErrorCode::ServerError(-32802),
        message: "the document changed; pull its diagnostics again".into(),
        data: Some(serde_json::json!({ "retriggerRequest": true })),
    }
}

impl Backend {
    /// Waits until every edit received so far is applied.
    async fn settled(&self) {
        let target = self.shared.enqueued.load(Ordering::SeqCst);
        let mut rx = self.applied.clone();
        let _ = rx.wait_for(|v| *v >= target).await;
    }

    /// Runs `f` on a snapshot, off the protocol task. Cancellation by a
    /// newer edit becomes `ContentModified`, a panic an internal error.
    async fn analyse<T, F>(&self, f: F) -> Result<T>
    where
        T: Send + 'static,
        F: FnOnce(&Analysis<'_>) -> T + Send + 'static,
    {
        self.analyse_or(content_modified, f).await
    }

    /// [`Self::analyse`], answering `stale()` when an edit cancels it.
    async fn analyse_or<T, F>(&self, stale: fn() -> Error, f: F) -> Result<T>
    where
        T: Send + 'static,
        F: FnOnce(&Analysis<'_>) -> T + Send + 'static,
    {
        self.settled().await;
        let shared = self.shared.clone();
        let res = tokio::task::spawn_blocking(move || {
            let snap = shared.host.snapshot();
            let a = Analysis::new(&snap.db, &snap.world);
            salsa::Cancelled::catch(AssertUnwindSafe(|| f(&a)))
        })
        .await;
        match res {
            Ok(Ok(v)) => Ok(v),
            Ok(Err(_cancelled)) => Err(stale()),
            Err(e) => {
                let mut err = Error::internal_error();
                err.message = format!("the request failed: {e}").into();
                Err(err)
            }
        }
    }
}

fn at(a: &Analysis<'_>, p: &TextDocumentPositionParams) -> (mcl_compiler::SourceFile, usize) {
    let file = a.file(&p.text_document.uri);
    (file, a.offset(file, p.position))
}

impl LanguageServer for Backend {
    async fn initialize(&self, params: InitializeParams) -> Result<InitializeResult> {
        let caps = &params.capabilities;
        let td = caps.text_document.as_ref();
        let snippets = td
            .and_then(|t| t.completion.as_ref())
            .and_then(|c| c.completion_item.as_ref())
            .and_then(|c| c.snippet_support)
            .unwrap_or(false);
        let pull = td.and_then(|t| t.diagnostic.as_ref()).is_some();
        let ws = caps.workspace.as_ref();
        let refresh = ws.and_then(|w| w.diagnostics.as_ref()).and_then(|d| d.refresh_support).unwrap_or(false);
        let watch =
            ws.and_then(|w| w.did_change_watched_files.as_ref()).and_then(|d| d.dynamic_registration).unwrap_or(false);
        let c = &self.shared.caps;
        c.snippets.store(snippets, Ordering::SeqCst);
        c.pull_diagnostics.store(pull, Ordering::SeqCst);
        c.diagnostic_refresh.store(refresh, Ordering::SeqCst);
        c.watch_registration.store(watch, Ordering::SeqCst);

        let mut roots: Vec<PathBuf> = Vec::new();
        for f in params.workspace_folders.iter().flatten() {
            roots.push(analysis::path_of_uri(&f.uri));
        }
        #[allow(deprecated)]
        if roots.is_empty() {
            if let Some(u) = &params.root_uri {
                roots.push(analysis::path_of_uri(u));
            }
        }
        roots.retain(|r| r.is_dir());
        *lock(&self.shared.root) = roots.first().cloned();
        if let Some(opts) = &params.initialization_options {
            *lock(&self.shared.bridge) = analysis::bridge::configured(opts, roots.first().map(PathBuf::as_path));
        }
        if !roots.is_empty() {
            // Off the edit path: a large folder must not delay the first edits.
            let shared = self.shared.clone();
            std::thread::spawn(move || {
                let files = crate::host::scan_workspace(&roots);
                shared.enqueue(Edit::Workspace { files });
            });
        }

        let capabilities = ServerCapabilities {
            position_encoding: Some(PositionEncodingKind::UTF16),
            text_document_sync: Some(TextDocumentSyncCapability::Options(TextDocumentSyncOptions {
                open_close: Some(true),
                change: Some(TextDocumentSyncKind::INCREMENTAL),
                ..Default::default()
            })),
            hover_provider: Some(HoverProviderCapability::Simple(true)),
            definition_provider: Some(OneOf::Left(true)),
            references_provider: Some(OneOf::Left(true)),
            document_highlight_provider: Some(OneOf::Left(true)),
            rename_provider: Some(OneOf::Right(RenameOptions {
                prepare_provider: Some(true),
                work_done_progress_options: Default::default(),
            })),
            completion_provider: Some(CompletionOptions {
                trigger_characters: Some(vec![":".into(), ">".into(), ",".into(), "{".into()]),
                ..Default::default()
            }),
            signature_help_provider: Some(SignatureHelpOptions {
                trigger_characters: Some(vec!["(".into(), ",".into()]),
                retrigger_characters: None,
                work_done_progress_options: Default::default(),
            }),
            document_symbol_provider: Some(OneOf::Left(true)),
            workspace_symbol_provider: Some(OneOf::Left(true)),
            semantic_tokens_provider: Some(SemanticTokensServerCapabilities::SemanticTokensOptions(
                SemanticTokensOptions {
                    legend: analysis::semantic::legend(),
                    full: Some(SemanticTokensFullOptions::Bool(true)),
                    range: None,
                    work_done_progress_options: Default::default(),
                },
            )),
            folding_range_provider: Some(FoldingRangeProviderCapability::Simple(true)),
            inlay_hint_provider: Some(OneOf::Left(true)),
            code_action_provider: Some(CodeActionProviderCapability::Options(CodeActionOptions {
                code_action_kinds: Some(vec![CodeActionKind::QUICKFIX]),
                ..Default::default()
            })),
            document_formatting_provider: crate::format::AVAILABLE.then_some(OneOf::Left(true)),
            diagnostic_provider: pull.then(|| {
                DiagnosticServerCapabilities::Options(DiagnosticOptions {
                    identifier: Some("mcl".into()),
                    inter_file_dependencies: true,
                    workspace_diagnostics: false,
                    work_done_progress_options: Default::default(),
                })
            }),
            ..Default::default()
        };
        Ok(InitializeResult {
            capabilities,
            server_info: Some(ServerInfo { name: "mcl-lsp".into(), version: Some(env!("CARGO_PKG_VERSION").into()) }),
            offset_encoding: None,
        })
    }

    async fn initialized(&self, _: InitializedParams) {
        if self.shared.caps.watch_registration.load(Ordering::SeqCst) {
            let watchers = ["**/*.mcl", "**/*.xml", "**/*.pnml", "**/*.toml", "**/*.msg", "**/*.srv", "**/*.action"]
                .iter()
                .map(|g| FileSystemWatcher { glob_pattern: GlobPattern::String(g.to_string()), kind: None })
                .collect();
            let opts = DidChangeWatchedFilesRegistrationOptions { watchers };
            let reg = Registration {
                id: "mcl-watch".into(),
                method: "workspace/didChangeWatchedFiles".into(),
                register_options: serde_json::to_value(opts).ok(),
            };
            let _ = self.client.register_capability(vec![reg]).await;
        }
    }

    async fn shutdown(&self) -> Result<()> {
        self.shared.shut_down.store(true, Ordering::SeqCst);
        Ok(())
    }

    // Edits are taken off the wire by `Ordered`; these never run.
    async fn did_open(&self, _: DidOpenTextDocumentParams) {}
    async fn did_change(&self, _: DidChangeTextDocumentParams) {}
    async fn did_close(&self, _: DidCloseTextDocumentParams) {}
    async fn did_change_watched_files(&self, _: DidChangeWatchedFilesParams) {}

    async fn did_change_configuration(&self, p: DidChangeConfigurationParams) {
        // `{"mcl": {"ros2Bridge": PATH}}`: the bridge file to check, or none.
        let root = lock(&self.shared.root).clone();
        let bridge = analysis::bridge::configured(&p.settings, root.as_deref());
        let changed = {
            let mut b = lock(&self.shared.bridge);
            let changed = *b != bridge;
            *b = bridge;
            changed
        };
        if changed {
            // An empty batch of watched files: a diagnostics pass.
            self.shared.enqueue(Edit::Watched { changes: Vec::new() });
        }
    }

    async fn hover(&self, p: HoverParams) -> Result<Option<Hover>> {
        self.analyse(move |a| {
            let (file, off) = at(a, &p.text_document_position_params);
            analysis::hover::hover(a, file, off)
        })
        .await
    }

    async fn goto_definition(&self, p: GotoDefinitionParams) -> Result<Option<GotoDefinitionResponse>> {
        self.analyse(move |a| {
            let (file, off) = at(a, &p.text_document_position_params);
            let locs = analysis::navigation::goto_definition(a, file, off);
            match locs.len() {
                0 => None,
                1 => Some(GotoDefinitionResponse::Scalar(locs.into_iter().next()?)),
                _ => Some(GotoDefinitionResponse::Array(locs)),
            }
        })
        .await
    }

    async fn references(&self, p: ReferenceParams) -> Result<Option<Vec<Location>>> {
        self.analyse(move |a| {
            let (file, off) = at(a, &p.text_document_position);
            Some(analysis::navigation::references(a, file, off, p.context.include_declaration))
        })
        .await
    }

    async fn document_highlight(&self, p: DocumentHighlightParams) -> Result<Option<Vec<DocumentHighlight>>> {
        self.analyse(move |a| {
            let (file, off) = at(a, &p.text_document_position_params);
            Some(analysis::navigation::highlights(a, file, off))
        })
        .await
    }

    async fn prepare_rename(&self, p: TextDocumentPositionParams) -> Result<Option<PrepareRenameResponse>> {
        let r = self
            .analyse(move |a| {
                let (file, off) = at(a, &p);
                analysis::navigation::prepare_rename(a, file, off)
            })
            .await?;
        r.map(Some).map_err(|e| Error::invalid_params(e.0))
    }

    async fn rename(&self, p: RenameParams) -> Result<Option<WorkspaceEdit>> {
        let r = self
            .analyse(move |a| {
                let (file, off) = at(a, &p.text_document_position);
                analysis::navigation::rename(a, file, off, &p.new_name)
            })
            .await?;
        r.map(Some).map_err(|e| Error::invalid_params(e.0))
    }

    async fn completion(&self, p: CompletionParams) -> Result<Option<CompletionResponse>> {
        let snippets = self.shared.caps.snippets.load(Ordering::SeqCst);
        self.analyse(move |a| {
            let (file, off) = at(a, &p.text_document_position);
            let items = analysis::completion::completion(a, file, off, snippets);
            Some(CompletionResponse::Array(items))
        })
        .await
    }

    async fn signature_help(&self, p: SignatureHelpParams) -> Result<Option<SignatureHelp>> {
        self.analyse(move |a| {
            let (file, off) = at(a, &p.text_document_position_params);
            analysis::completion::signature_help(a, file, off)
        })
        .await
    }

    async fn document_symbol(&self, p: DocumentSymbolParams) -> Result<Option<DocumentSymbolResponse>> {
        self.analyse(move |a| {
            let file = a.file(&p.text_document.uri);
            Some(DocumentSymbolResponse::Nested(analysis::outline::document_symbols(a, file)))
        })
        .await
    }

    async fn symbol(&self, p: WorkspaceSymbolParams) -> Result<Option<WorkspaceSymbolResponse>> {
        self.analyse(move |a| Some(WorkspaceSymbolResponse::Flat(analysis::outline::workspace_symbols(a, &p.query))))
            .await
    }

    async fn semantic_tokens_full(&self, p: SemanticTokensParams) -> Result<Option<SemanticTokensResult>> {
        self.analyse(move |a| {
            let file = a.file(&p.text_document.uri);
            let data = analysis::semantic::semantic_tokens(a, file);
            Some(SemanticTokensResult::Tokens(SemanticTokens { result_id: None, data }))
        })
        .await
    }

    async fn folding_range(&self, p: FoldingRangeParams) -> Result<Option<Vec<FoldingRange>>> {
        self.analyse(move |a| {
            let file = a.file(&p.text_document.uri);
            Some(analysis::outline::folding_ranges(a, file))
        })
        .await
    }

    async fn inlay_hint(&self, p: InlayHintParams) -> Result<Option<Vec<InlayHint>>> {
        self.analyse(move |a| {
            let file = a.file(&p.text_document.uri);
            let span = a.span_of(file, p.range);
            Some(analysis::semantic::inlay_hints(a, file, span))
        })
        .await
    }

    async fn code_action(&self, p: CodeActionParams) -> Result<Option<CodeActionResponse>> {
        self.analyse(move |a| {
            let file = a.file(&p.text_document.uri);
            let span = a.span_of(file, p.range);
            let actions = analysis::fixes::code_actions(a, file, span);
            Some(actions.into_iter().map(CodeActionOrCommand::CodeAction).collect())
        })
        .await
    }

    async fn formatting(&self, p: DocumentFormattingParams) -> Result<Option<Vec<TextEdit>>> {
        self.analyse(move |a| {
            let file = a.file(&p.text_document.uri);
            crate::format::format_document(a, file)
        })
        .await
    }

    async fn diagnostic(&self, p: DocumentDiagnosticParams) -> Result<DocumentDiagnosticReportResult> {
        // The compiler's diagnostics, and the coordination verdict when it
        // is still valid. Otherwise the analysis thread computes it and asks
        // the client to pull again; a client that cannot be asked waits for it.
        let refresh = self.shared.caps.diagnostic_refresh.load(Ordering::SeqCst);
        let shared = self.shared.clone();
        let seen = self.shared.text_edits.load(Ordering::SeqCst);
        let items = self
            .analyse_or(server_cancelled, move |a| {
                let file = a.file(&p.text_document.uri);
                let mut items = analysis::diagnostics::semantic(a, file);
                let verdict = match shared.coord(a, file) {
                    Coord::Valid(d) => d,
                    Coord::Stale(fp) if !refresh => shared.compute_verdict(a, file, fp).0,
                    Coord::Stale(_) | Coord::None => Vec::new(),
                };
                items.extend(verdict.iter().map(|d| analysis::diagnostics::to_lsp(a, file, d)));
                items
            })
            .await?;
        // An edit came while this was computed: the client pulls again.
        if self.shared.text_edits.load(Ordering::SeqCst) > seen {
            return Err(server_cancelled());
        }
        Ok(DocumentDiagnosticReportResult::Report(DocumentDiagnosticReport::Full(
            RelatedFullDocumentDiagnosticReport {
                related_documents: None,
                full_document_diagnostic_report: FullDocumentDiagnosticReport { result_id: None, items },
            },
        )))
    }
}

/// Takes the document edits off the wire in arrival order (the transport
/// calls `call` in order, but runs the handlers' futures concurrently).
pub struct Ordered {
    inner: LspService<Backend>,
    shared: Arc<Shared>,
}

fn edit_of(method: &str, params: Option<serde_json::Value>) -> Option<Edit> {
    let params = params?;
    Some(match method {
        "textDocument/didOpen" => {
            let p: DidOpenTextDocumentParams = serde_json::from_value(params).ok()?;
            Edit::Open { uri: p.text_document.uri, version: p.text_document.version, text: p.text_document.text }
        }
        "textDocument/didChange" => {
            let p: DidChangeTextDocumentParams = serde_json::from_value(params).ok()?;
            Edit::Change { uri: p.text_document.uri, version: p.text_document.version, changes: p.content_changes }
        }
        "textDocument/didClose" => {
            let p: DidCloseTextDocumentParams = serde_json::from_value(params).ok()?;
            Edit::Close { uri: p.text_document.uri }
        }
        "workspace/didChangeWatchedFiles" => {
            let p: DidChangeWatchedFilesParams = serde_json::from_value(params).ok()?;
            Edit::Watched { changes: p.changes }
        }
        _ => return None,
    })
}

impl tower::Service<Request> for Ordered {
    type Response = Option<Response>;
    type Error = tower_lsp_server::ExitedError;
    type Future = <LspService<Backend> as tower::Service<Request>>::Future;

    fn poll_ready(&mut self, cx: &mut Context<'_>) -> Poll<std::result::Result<(), Self::Error>> {
        self.inner.poll_ready(cx)
    }

    fn call(&mut self, req: Request) -> Self::Future {
        let is_edit = matches!(
            req.method(),
            "textDocument/didOpen"
                | "textDocument/didChange"
                | "textDocument/didClose"
                | "workspace/didChangeWatchedFiles"
        ) && req.id().is_none();
        if is_edit {
            let (method, _, params) = req.into_parts();
            match edit_of(&method, params) {
                Some(edit) => self.shared.enqueue(edit),
                None => eprintln!("mcl-lsp: ignoring a malformed `{method}` notification"),
            }
            return Box::pin(async { Ok(None) });
        }
        if req.method() == "exit" {
            self.shared.exit.notify_one();
        }
        self.inner.call(req)
    }
}

/// A diagnostics publication for the publisher task.
struct Publication {
    uri: Uri,
    version: Option<i32>,
    generation: u64,
    /// 0: syntax only, 1: complete.
    stage: u8,
    diagnostics: Vec<Diagnostic>,
}

enum ToClient {
    Publish(Publication),
    Refresh,
}

/// The analysis thread: after each batch of edits, diagnostics of the
/// affected files, on a snapshot; abandoned when cancelled (the next batch
/// wakes it again, and pending changes are kept until a pass completes).
fn analysis_loop(shared: Arc<Shared>, wake: mpsc::Receiver<()>, out: tmpsc::UnboundedSender<ToClient>) {
    // Files whose diagnostics are shown, by path.
    let mut shown: HashMap<PathBuf, Uri> = HashMap::new();
    while wake.recv().is_ok() {
        while wake.try_recv().is_ok() {}
        let (snap, pending, closed) = {
            let s = shared.host.lock();
            let snap = Snapshot { db: s.db.clone(), world: s.world.clone(), generation: s.generation };
            (snap, s.pending.clone(), s.closed.clone())
        };
        let generation = snap.generation;
        let pull = shared.caps.pull_diagnostics.load(Ordering::SeqCst);
        let result = std::panic::catch_unwind(AssertUnwindSafe(|| {
            diagnostics_pass(&shared, &snap, &pending, &closed, pull, &shown, &out)
        }));
        drop(snap); // before locking the host again: an edit may be waiting for it
        let result = match result {
            Ok(pass) => Some(pass),
            Err(payload) if payload.downcast_ref::<salsa::Cancelled>().is_some() => None,
            Err(_) => {
                // A bug in a check: drop these changes rather than fail again on each wake.
                eprintln!("mcl-lsp: computing diagnostics failed");
                let mut s = shared.host.lock();
                s.pending.retain(|(g, _)| *g > generation);
                s.closed.retain(|(g, _)| *g > generation);
                None
            }
        };
        if let Some(pass) = result {
            let mut s = shared.host.lock();
            s.pending.retain(|(g, _)| *g > generation);
            s.closed.retain(|(g, _)| *g > generation);
            drop(s);
            shown = pass.shown;
            if pass.refresh && shared.caps.diagnostic_refresh.load(Ordering::SeqCst) {
                let _ = out.send(ToClient::Refresh);
            }
        }
        // Cancelled: a newer batch has woken us already.
    }
}

struct Pass {
    /// Pull mode: documents other than the edited ones are affected.
    refresh: bool,
    shown: HashMap<PathBuf, Uri>,
}

fn diagnostics_pass(
    shared: &Shared,
    snap: &Snapshot,
    pending: &[(u64, PathBuf)],
    closed: &[(u64, Uri)],
    pull: bool,
    shown: &HashMap<PathBuf, Uri>,
    out: &tmpsc::UnboundedSender<ToClient>,
) -> Pass {
    let a = Analysis::new(&snap.db, &snap.world);
    let changed: HashSet<&PathBuf> = pending.iter().map(|(_, p)| p).collect();
    let targets = a.diagnosed_files();
    let mut now_shown = HashMap::new();
    let mut affected = Vec::new();
    for &f in &targets {
        let path = a.path(f).to_path_buf();
        let touched = program(&snap.db, f).files.iter().any(|g| changed.contains(&a.path(*g).to_path_buf()));
        if touched || !shown.contains_key(&path) {
            affected.push(f);
        }
        if let Some(uri) = a.uri(f) {
            now_shown.insert(path, uri);
        }
    }
    // The edited documents first.
    affected.sort_by_key(|f| !changed.contains(&a.path(*f).to_path_buf()));
    if pull {
        // The client asks for each document's diagnostics; tell it to ask
        // again when a change reaches documents other than the edited ones,
        // or when a new coordination verdict is ready.
        let mut refresh = affected.iter().any(|f| !changed.contains(&a.path(*f).to_path_buf()));
        for &f in &affected {
            // A request may have answered without this verdict meanwhile.
            if let Coord::Stale(fp) = shared.coord(&a, f) {
                let (verdict, changed) = shared.compute_verdict(&a, f, fp);
                refresh |= changed || !verdict.is_empty();
            }
        }
        // The bridge file's errors, pushed on its own URI all the same.
        bridge_pass(shared, &a, snap.generation, out);
        return Pass { refresh, shown: HashMap::new() };
    }
    let gen = snap.generation;
    let send = |uri: Uri, version: Option<i32>, stage: u8, diagnostics: Vec<Diagnostic>| {
        let _ = out.send(ToClient::Publish(Publication { uri, version, generation: gen, stage, diagnostics }));
    };
    // Files no longer diagnosed (closed, and imported by no open document): clear.
    let mut cleared: HashSet<String> = HashSet::new();
    for (path, uri) in shown {
        if !now_shown.contains_key(path) && cleared.insert(uri.as_str().to_string()) {
            send(uri.clone(), None, 1, vec![]);
        }
    }
    for (_, uri) in closed {
        let path = snap.world.path_of(uri);
        if !now_shown.contains_key(&path) && cleared.insert(uri.as_str().to_string()) {
            send(uri.clone(), None, 1, vec![]);
        }
    }
    // Syntax errors first: they are ready as soon as the file is parsed.
    for &f in &affected {
        let syntax = analysis::diagnostics::syntax(&a, f);
        if !syntax.is_empty() {
            if let Some(uri) = a.uri(f) {
                send(uri, a.world.version_of(a.path(f)), 0, syntax);
            }
        }
    }
    // Then the compiler's checks of every affected file, with the last
    // coordination verdict while it is still valid (an edit elsewhere in
    // the file does not hide it), and last the coordination analyses that
    // must run again, which can take seconds: a stage waits for none of the
    // slower ones, and an edit cancels them part-way.
    let to_lsp = |f, d: &[mcl_syntax::Diagnostic]| -> Vec<Diagnostic> {
        d.iter().map(|d| analysis::diagnostics::to_lsp(&a, f, d)).collect()
    };
    let mut semantic = Vec::with_capacity(affected.len());
    for &f in &affected {
        let diags = analysis::diagnostics::semantic(&a, f);
        // The last verdict, carried to the current text; checked below.
        let carried = shared.carried(&a, f);
        let mut shown = diags.clone();
        shown.extend(to_lsp(f, carried.as_deref().unwrap_or_default()));
        if let Some(uri) = a.uri(f) {
            send(uri, a.world.version_of(a.path(f)), 1, shown);
        }
        semantic.push((diags, carried.is_some()));
    }
    // The bridge file's errors (it needs the vehicle: after the compiler's
    // checks, before the slow coordination analyses).
    bridge_pass(shared, &a, gen, out);
    for (&f, (mut diags, carried)) in affected.iter().zip(semantic) {
        let fingerprint = match shared.coord(&a, f) {
            Coord::Valid(_) => continue, // shown as carried (or empty)
            Coord::None => None,
            Coord::Stale(fp) => Some(fp),
        };
        // The carried verdict no longer holds: withdraw it at once.
        if carried {
            if let Some(uri) = a.uri(f) {
                send(uri, a.world.version_of(a.path(f)), 1, diags.clone());
            }
        }
        let Some(fp) = fingerprint else { continue };
        let (verdict, _) = shared.compute_verdict(&a, f, fp);
        if verdict.is_empty() {
            continue;
        }
        diags.extend(to_lsp(f, &verdict));
        if let Some(uri) = a.uri(f) {
            send(uri, a.world.version_of(a.path(f)), 2, diags);
        }
    }
    Pass { refresh: false, shown: now_shown }
}

/// Publishes the errors of the configured ROS 2 bridge file, and clears
/// those of files that no longer have any to show.
fn bridge_pass(shared: &Shared, a: &Analysis<'_>, generation: u64, out: &tmpsc::UnboundedSender<ToClient>) {
    let bridge = lock(&shared.bridge).clone();
    let found = bridge.map(|b| analysis::bridge::diagnostics(a, &b)).unwrap_or_default();
    let mut now = HashSet::new();
    for (path, diagnostics) in found {
        let Some(uri) = a.world.uri_of(&path) else { continue };
        now.insert(uri.as_str().to_string());
        let version = a.world.version_of(&path);
        let _ = out.send(ToClient::Publish(Publication { uri, version, generation, stage: 1, diagnostics }));
    }
    let mut shown = lock(&shared.bridge_shown);
    for old in shown.difference(&now) {
        if let Ok(uri) = old.parse::<Uri>() {
            let p = Publication { uri, version: None, generation, stage: 1, diagnostics: vec![] };
            let _ = out.send(ToClient::Publish(p));
        }
    }
    *shown = now;
}

/// Sends publications in order, dropping any older than one already sent
/// for the same document.
async fn publisher(client: Client, mut rx: tmpsc::UnboundedReceiver<ToClient>) {
    let mut last: HashMap<String, (u64, u8)> = HashMap::new();
    while let Some(msg) = rx.recv().await {
        match msg {
            ToClient::Publish(p) => {
                let key = p.uri.as_str().to_string();
                if last.get(&key).is_some_and(|&l| l > (p.generation, p.stage)) {
                    continue;
                }
                last.insert(key, (p.generation, p.stage));
                client.publish_diagnostics(p.uri, p.diagnostics, p.version).await;
            }
            ToClient::Refresh => {
                let _ = client.workspace_diagnostic_refresh().await;
            }
        }
    }
}

/// The host thread: applies edits in order, then wakes the analysis thread.
fn host_loop(
    shared: Arc<Shared>,
    rx: mpsc::Receiver<(u64, Edit)>,
    applied: watch::Sender<u64>,
    wake: mpsc::Sender<()>,
) {
    while let Ok(first) = rx.recv() {
        let mut last = first.0;
        let mut batch = vec![first.1];
        while let Ok((seq, e)) = rx.try_recv() {
            last = last.max(seq);
            batch.push(e);
        }
        // A bug while applying must not stop the server: later edits and
        // every request wait on this thread.
        if std::panic::catch_unwind(AssertUnwindSafe(|| shared.host.apply(batch))).is_err() {
            eprintln!("mcl-lsp: applying an edit failed");
        }
        let _ = applied.send(last);
        let _ = wake.send(());
    }
}

/// Builds the service and starts its threads.
pub fn service() -> (Ordered, tower_lsp_server::ClientSocket) {
    let (edit_tx, edit_rx) = mpsc::channel();
    let shared = Arc::new(Shared {
        host: Host::new(),
        caps: Caps::default(),
        enqueued: AtomicU64::new(0),
        text_edits: AtomicU64::new(0),
        edits: std::sync::Mutex::new(edit_tx),
        shut_down: AtomicBool::new(false),
        exit: tokio::sync::Notify::new(),
        verdicts: Default::default(),
        bridge: Default::default(),
        root: Default::default(),
        bridge_shown: Default::default(),
    });
    let (applied_tx, applied_rx) = watch::channel(0u64);
    let (wake_tx, wake_rx) = mpsc::channel();
    let (out_tx, out_rx) = tmpsc::unbounded_channel();
    {
        let shared = shared.clone();
        std::thread::Builder::new()
            .name("mcl-lsp-host".into())
            .spawn(move || host_loop(shared, edit_rx, applied_tx, wake_tx))
            .expect("spawn host thread");
    }
    {
        let shared = shared.clone();
        std::thread::Builder::new()
            .name("mcl-lsp-analysis".into())
            .spawn(move || analysis_loop(shared, wake_rx, out_tx))
            .expect("spawn analysis thread");
    }
    let shared2 = shared.clone();
    let (inner, socket) = LspService::new(move |client| {
        tokio::spawn(publisher(client.clone(), out_rx));
        Backend { client, shared: shared2, applied: applied_rx }
    });
    (Ordered { inner, shared }, socket)
}

/// Serves the protocol on the given streams until `exit` (or the end of the
/// input). Returns whether the client asked for `shutdown` first.
pub async fn serve<I, O>(input: I, output: O) -> bool
where
    I: tokio::io::AsyncRead + Unpin + Send + 'static,
    O: tokio::io::AsyncWrite,
{
    let (service, socket) = service();
    let shared = service.shared.clone();
    tokio::select! {
        _ = Server::new(crate::framing::resync(input), output, socket).serve(service) => {}
        _ = shared.exit.notified() => {}
    }
    shared.shut_down.load(Ordering::SeqCst)
}

/// `mcl lsp`: serves on standard input and output. Returns the exit status:
/// 0 after `shutdown` and `exit`, 1 when the client exits (or goes away)
/// without `shutdown`, as the protocol says.
pub fn run_stdio() -> u8 {
    let rt = match tokio::runtime::Builder::new_multi_thread().worker_threads(2).enable_all().build() {
        Ok(rt) => rt,
        Err(e) => {
            eprintln!("mcl lsp: cannot start the runtime: {e}");
            return 2;
        }
    };
    let clean = rt.block_on(serve(tokio::io::stdin(), tokio::io::stdout()));
    // Threads blocked on stdin or on the analysis channel end with the process.
    rt.shutdown_timeout(std::time::Duration::from_millis(100));
    if clean {
        0
    } else {
        1
    }
}
