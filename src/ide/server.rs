//! The language server: one message at a time from the client. Every open file is compiled
//! whole, with its libraries, each time it changes (`BENCHMARKS.md`, "Language server": a
//! 1,000-line file in 13 to 20 ms of CPU time), and its diagnostics are published; requests read the
//! latest analysis of their file.

use std::collections::{BTreeSet, HashMap};
use std::path::{Path, PathBuf};

use lsp_server::{Connection, ErrorCode, Message, Notification, Request, Response};
use lsp_types::notification::{
    DidChangeTextDocument, DidCloseTextDocument, DidOpenTextDocument, Notification as _,
    PublishDiagnostics,
};
use lsp_types::request::{
    CodeActionRequest, Completion, DocumentSymbolRequest, Formatting, GotoDefinition, HoverRequest,
    References, Rename, Request as _, SemanticTokensFullRequest,
};
use lsp_types::{
    CodeActionProviderCapability, CompletionOptions, OneOf, PublishDiagnosticsParams,
    SemanticTokens, SemanticTokensFullOptions, SemanticTokensOptions,
    SemanticTokensServerCapabilities, ServerCapabilities, TextDocumentPositionParams,
    TextDocumentSyncCapability, TextDocumentSyncKind, TextEdit, Uri,
};
use serde_json::Value;

use crate::ide::across::{self, Target};
use crate::ide::analysis::Analysis;
use crate::ide::{actions, complete, convert, format, manifest, navigate, outline};
use crate::load::LoadOptions;

type Error = Box<dyn std::error::Error + Send + Sync>;

/// Serves one client on standard input and output until it exits.
pub fn run_stdio() -> Result<(), Error> {
    let (connection, io_threads) = Connection::stdio();
    serve(&connection)?;
    drop(connection);
    io_threads.join()?;
    Ok(())
}

/// What the server can do, announced at initialisation.
pub fn capabilities() -> ServerCapabilities {
    ServerCapabilities {
        text_document_sync: Some(TextDocumentSyncCapability::Kind(TextDocumentSyncKind::FULL)),
        hover_provider: Some(lsp_types::HoverProviderCapability::Simple(true)),
        definition_provider: Some(OneOf::Left(true)),
        references_provider: Some(OneOf::Left(true)),
        completion_provider: Some(CompletionOptions {
            trigger_characters: Some(vec![".".into(), ":".into(), "(".into(), " ".into()]),
            ..Default::default()
        }),
        document_symbol_provider: Some(OneOf::Left(true)),
        rename_provider: Some(OneOf::Left(true)),
        code_action_provider: Some(CodeActionProviderCapability::Simple(true)),
        document_formatting_provider: Some(OneOf::Left(true)),
        semantic_tokens_provider: Some(SemanticTokensServerCapabilities::SemanticTokensOptions(
            SemanticTokensOptions {
                legend: outline::legend(),
                full: Some(SemanticTokensFullOptions::Bool(true)),
                ..Default::default()
            },
        )),
        ..Default::default()
    }
}

/// Answers the client's messages until it asks the server to shut down.
pub fn serve(connection: &Connection) -> Result<(), Error> {
    let (id, _params) = connection.initialize_start()?;
    // `serverInfo` tells the client which server and version answers (LSP 3.15).
    let result = serde_json::json!({
        "capabilities": capabilities(),
        "serverInfo": { "name": "lsdc", "version": env!("CARGO_PKG_VERSION") },
    });
    connection.initialize_finish(id, result)?;
    let mut server = Server {
        documents: HashMap::new(),
        last_parsed: HashMap::new(),
        manifests: HashMap::new(),
        options: LoadOptions::default(),
    };
    for message in &connection.receiver {
        match message {
            Message::Request(request) => {
                if connection.handle_shutdown(&request)? {
                    return Ok(());
                }
                let response = server.request(request);
                connection.sender.send(Message::Response(response))?;
            }
            Message::Notification(notification) => {
                for published in server.notification(notification) {
                    connection.sender.send(Message::Notification(published))?;
                }
            }
            Message::Response(_) => {}
        }
    }
    Ok(())
}

struct Server {
    /// The open files, by URI, each with its latest analysis.
    documents: HashMap<Uri, Analysis>,
    /// For an open file that does not parse at all (the parser reached its end inside a
    /// declaration): its latest analysis that had declarations, for completion's names.
    last_parsed: HashMap<Uri, Analysis>,
    /// The open test manifests (`lsdtest.toml`), by URI, with their text: not LSD, completed
    /// with the scenes of their cases' programs (`manifest`).
    manifests: HashMap<Uri, String>,
    options: LoadOptions,
}

impl Server {
    /// Opened, changed or closed files: their diagnostics to publish.
    fn notification(&mut self, notification: Notification) -> Vec<Notification> {
        let (uri, text) = match notification.method.as_str() {
            DidOpenTextDocument::METHOD => {
                match serde_json::from_value::<lsp_types::DidOpenTextDocumentParams>(
                    notification.params,
                ) {
                    Ok(params) => (params.text_document.uri, Some(params.text_document.text)),
                    Err(_) => return Vec::new(),
                }
            }
            DidChangeTextDocument::METHOD => {
                match serde_json::from_value::<lsp_types::DidChangeTextDocumentParams>(
                    notification.params,
                ) {
                    // Full synchronisation: the last change is the whole text.
                    Ok(params) => (
                        params.text_document.uri,
                        params.content_changes.into_iter().last().map(|c| c.text),
                    ),
                    Err(_) => return Vec::new(),
                }
            }
            DidCloseTextDocument::METHOD => {
                if let Ok(params) = serde_json::from_value::<lsp_types::DidCloseTextDocumentParams>(
                    notification.params,
                ) {
                    self.documents.remove(&params.text_document.uri);
                    self.last_parsed.remove(&params.text_document.uri);
                    self.manifests.remove(&params.text_document.uri);
                    return vec![publish(params.text_document.uri, Vec::new())];
                }
                return Vec::new();
            }
            _ => return Vec::new(),
        };
        let Some(text) = text else {
            return Vec::new();
        };
        let path = convert::uri_to_path(&uri).unwrap_or_else(|| PathBuf::from(uri.as_str()));
        if manifest::is_manifest(&path) {
            self.manifests.insert(uri, text);
            return Vec::new();
        }
        let analysis = Analysis::new(&path, &text, &self.options);
        let diagnostics = analysis
            .compilation
            .diagnostics
            .iter()
            .map(|d| convert::diagnostic(&analysis, d))
            .collect();
        let parsed = has_declarations(&analysis);
        if let Some(previous) = self.documents.insert(uri.clone(), analysis) {
            if parsed {
                self.last_parsed.remove(&uri);
            } else if has_declarations(&previous) {
                self.last_parsed.insert(uri.clone(), previous);
            }
        }
        vec![publish(uri, diagnostics)]
    }

    fn request(&mut self, request: Request) -> Response {
        let id = request.id.clone();
        match self.answer(request) {
            Ok(result) => Response::new_ok(id, result),
            Err(message) => Response::new_err(id, ErrorCode::RequestFailed as i32, message),
        }
    }

    fn answer(&mut self, request: Request) -> Result<Value, String> {
        let method = request.method.as_str();
        let params = request.params;
        let json = |value: Result<Value, serde_json::Error>| value.map_err(|e| e.to_string());
        match method {
            HoverRequest::METHOD => {
                let (analysis, offset) = self.at(params)?;
                json(serde_json::to_value(navigate::hover(analysis, offset)))
            }
            GotoDefinition::METHOD => {
                let (analysis, offset) = self.at(params)?;
                json(serde_json::to_value(navigate::definition(analysis, offset)))
            }
            References::METHOD => {
                let declaration = params["context"]["includeDeclaration"]
                    .as_bool()
                    .unwrap_or(true);
                let (analysis, offset) = self.at(params)?;
                let Some(target) = Target::at(analysis, offset) else {
                    return Ok(Value::Array(Vec::new()));
                };
                let closed = self.readable_importers(&target);
                let analyses = self.with_open(&closed);
                json(serde_json::to_value(across::references(
                    &analyses,
                    &target,
                    declaration,
                )))
            }
            Rename::METHOD => {
                let new_name = params["newName"].as_str().unwrap_or_default().to_string();
                let (analysis, offset) = self.at(params)?;
                let target =
                    Target::at(analysis, offset).ok_or("no name defined in this program here")?;
                let closed = self.readable_importers(&target);
                let analyses = self.with_open(&closed);
                json(serde_json::to_value(across::rename(
                    &analyses, &target, &new_name,
                )?))
            }
            Completion::METHOD => {
                let uri: Uri = serde_json::from_value(params["textDocument"]["uri"].clone())
                    .map_err(|e| e.to_string())?;
                if let Some(text) = self.manifests.get(&uri) {
                    return json(serde_json::to_value(
                        self.manifest_completions(&uri, text, params)?,
                    ));
                }
                let (analysis, offset) = self.at(params)?;
                let names = self.last_parsed.get(&uri).unwrap_or(analysis);
                json(serde_json::to_value(complete::completions(
                    analysis, names, offset,
                )))
            }
            DocumentSymbolRequest::METHOD => {
                let analysis = self.document(&params)?;
                json(serde_json::to_value(outline::document_symbols(analysis)))
            }
            SemanticTokensFullRequest::METHOD => {
                let analysis = self.document(&params)?;
                let tokens = SemanticTokens {
                    result_id: None,
                    data: outline::semantic_tokens(analysis),
                };
                json(serde_json::to_value(tokens))
            }
            CodeActionRequest::METHOD => {
                let range =
                    serde_json::from_value(params["range"].clone()).map_err(|e| e.to_string())?;
                let analysis = self.document(&params)?;
                json(serde_json::to_value(actions::code_actions(analysis, range)))
            }
            Formatting::METHOD => {
                let analysis = self.document(&params)?;
                json(serde_json::to_value(formatting(analysis)?))
            }
            _ => Err(format!("unsupported request `{method}`")),
        }
    }

    /// The files beside the open ones (and beside the target's) that are not open and import
    /// the target's library, analysed from disk.
    fn readable_importers(&self, target: &Target) -> Vec<Analysis> {
        let open: BTreeSet<PathBuf> = (self.documents.keys())
            .filter_map(convert::uri_to_path)
            .map(|p| std::fs::canonicalize(&p).unwrap_or(p))
            .collect();
        let directories = (open.iter())
            .filter_map(|p| p.parent().map(Path::to_path_buf))
            .chain(target.directory())
            .collect();
        across::readable_importers(&directories, &open, target, &self.options)
    }

    /// The completions in the open manifest `uri` of text `text` at the position `params` name:
    /// its programs read from the open files, else from disk.
    fn manifest_completions(
        &self,
        uri: &Uri,
        text: &str,
        params: Value,
    ) -> Result<Vec<lsp_types::CompletionItem>, String> {
        let position: TextDocumentPositionParams =
            serde_json::from_value(params).map_err(|e| e.to_string())?;
        let offset = convert::offset(text, position.position);
        let path = convert::uri_to_path(uri).unwrap_or_else(|| PathBuf::from(uri.as_str()));
        let canonical = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
        let program_text = |program: &Path| {
            let open = (self.documents.iter()).find(|(uri, _)| {
                convert::uri_to_path(uri).is_some_and(|p| canonical(&p) == canonical(program))
            });
            match open {
                Some((_, analysis)) => Some(analysis.text(analysis.root).to_string()),
                None => std::fs::read_to_string(program).ok(),
            }
        };
        Ok(manifest::completions(
            &path,
            text,
            offset,
            &program_text,
            &self.options,
        ))
    }

    /// The open files' analyses, then `closed`.
    fn with_open<'a>(&'a self, closed: &'a [Analysis]) -> Vec<&'a Analysis> {
        self.documents.values().chain(closed).collect()
    }

    /// The analysis of the file a request names.
    fn document(&self, params: &Value) -> Result<&Analysis, String> {
        let uri: Uri = serde_json::from_value(params["textDocument"]["uri"].clone())
            .map_err(|e| e.to_string())?;
        self.documents
            .get(&uri)
            .ok_or_else(|| format!("`{}` is not open", uri.as_str()))
    }

    /// The analysis and the byte offset a positional request names.
    fn at(&self, params: Value) -> Result<(&Analysis, usize), String> {
        let analysis = self.document(&params)?;
        let position: TextDocumentPositionParams =
            serde_json::from_value(params).map_err(|e| e.to_string())?;
        let offset = convert::offset(analysis.text(analysis.root), position.position);
        Ok((analysis, offset))
    }
}

fn has_declarations(analysis: &Analysis) -> bool {
    let workspace = &analysis.compilation.workspace;
    !workspace
        .module(workspace.roots[0])
        .program
        .decls
        .is_empty()
}

fn publish(uri: Uri, diagnostics: Vec<lsp_types::Diagnostic>) -> Notification {
    let params = PublishDiagnosticsParams::new(uri, diagnostics, None);
    Notification::new(PublishDiagnostics::METHOD.to_string(), params)
}

/// The whole file formatted, as one edit; a file that does not parse is left alone.
fn formatting(analysis: &Analysis) -> Result<Vec<TextEdit>, String> {
    let text = analysis.text(analysis.root);
    let formatted = format::format(analysis.root, text).map_err(|diagnostics| {
        let first = diagnostics
            .first()
            .map(ToString::to_string)
            .unwrap_or_default();
        format!("the file does not parse: {first}")
    })?;
    if formatted == text {
        return Ok(Vec::new());
    }
    let range = convert::range(text, 0, text.len());
    Ok(vec![TextEdit::new(range, formatted)])
}
