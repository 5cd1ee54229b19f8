//! The language server driven over standard input and output as an editor drives it: JSON-RPC
//! messages with `Content-Length` headers, and assertions on the JSON it answers.

use std::io::{BufRead, BufReader, Read, Write};
use std::path::PathBuf;
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};

use serde_json::{json, Value};

struct Client {
    server: Child,
    input: ChildStdin,
    output: BufReader<ChildStdout>,
    next_id: i64,
    /// Notifications received while waiting for responses.
    notifications: Vec<Value>,
}

impl Client {
    fn start() -> Client {
        let mut server = Command::new(env!("CARGO_BIN_EXE_lsdc"))
            .arg("lsp")
            .env_remove("LSD_PATH")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .expect("lsdc lsp starts");
        let input = server.stdin.take().expect("stdin");
        let output = BufReader::new(server.stdout.take().expect("stdout"));
        Client {
            server,
            input,
            output,
            next_id: 0,
            notifications: Vec::new(),
        }
    }

    fn send(&mut self, message: Value) {
        let body = message.to_string();
        write!(self.input, "Content-Length: {}\r\n\r\n{body}", body.len()).expect("writes");
        self.input.flush().expect("flushes");
    }

    fn receive(&mut self) -> Value {
        let mut length = 0;
        loop {
            let mut line = String::new();
            self.output.read_line(&mut line).expect("reads a header");
            if let Some(value) = line.strip_prefix("Content-Length: ") {
                length = value.trim().parse().expect("a length");
            }
            if line == "\r\n" {
                break;
            }
        }
        let mut body = vec![0; length];
        self.output.read_exact(&mut body).expect("reads a body");
        serde_json::from_slice(&body).expect("JSON")
    }

    fn request(&mut self, method: &str, params: Value) -> Value {
        self.next_id += 1;
        let id = self.next_id;
        self.send(json!({"jsonrpc": "2.0", "id": id, "method": method, "params": params}));
        loop {
            let message = self.receive();
            if message["id"] == id {
                return message["result"].clone();
            }
            self.notifications.push(message);
        }
    }

    fn notify(&mut self, method: &str, params: Value) {
        self.send(json!({"jsonrpc": "2.0", "method": method, "params": params}));
    }

    /// The diagnostics published next.
    fn diagnostics(&mut self) -> Value {
        loop {
            let message = match self.notifications.pop() {
                Some(message) => message,
                None => self.receive(),
            };
            if message["method"] == "textDocument/publishDiagnostics" {
                return message["params"]["diagnostics"].clone();
            }
        }
    }
}

/// The labels of completion items.
fn labels(items: &Value) -> Vec<&str> {
    let items = items.as_array().expect("completion items");
    items.iter().filter_map(|i| i["label"].as_str()).collect()
}

fn file_uri(path: &std::path::Path) -> String {
    format!("file://{}", path.display())
}

/// The position of the `skip`-th character of `needle` in `text` (ASCII lines).
fn position(text: &str, needle: &str, skip: usize) -> Value {
    let offset = text.find(needle).expect("the needle is in the text") + skip;
    let line = text[..offset].matches('\n').count();
    let column = text[..offset]
        .chars()
        .rev()
        .take_while(|&c| c != '\n')
        .count();
    json!({"line": line, "character": column})
}

const WITH_ERRORS: &str = "import joints ;\n\
    let arm = body mass = 2, inertia = [0.1, 0.1, 0.01] end ;\n\
    join earth and arn with revolute([0, 1, 0]) as shoulder ;\n";

const FIXED: &str = "import joints ;\n\
    let arm = body mass = 2, inertia = [0.1, 0.1, 0.01] end ;\n\
    join earth and arm with revolute([0,1,0]) as shoulder ;\n\
    initial shoulder.q = 0.5 ;\n";

#[test]
fn a_session_with_every_request() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples/arm.lsd");
    let uri = file_uri(&path);
    let document = json!({"uri": uri});
    let mut client = Client::start();
    let initialized = client.request("initialize", json!({"capabilities": {}}));
    assert_eq!(initialized["capabilities"]["hoverProvider"], true);
    assert!(
        initialized["capabilities"]["semanticTokensProvider"]["legend"]["tokenTypes"].is_array()
    );
    client.notify("initialized", json!({}));

    // An error: the code, range, message and help of the command line.
    client.notify("textDocument/didOpen", json!({"textDocument": {"uri": uri, "languageId": "lsd", "version": 1, "text": WITH_ERRORS}}));
    let diagnostics = client.diagnostics();
    assert_eq!(
        diagnostics.as_array().map(Vec::len),
        Some(1),
        "{diagnostics}"
    );
    assert_eq!(diagnostics[0]["code"], "E0301");
    assert_eq!(
        diagnostics[0]["range"]["start"],
        json!({"line": 2, "character": 15})
    );
    assert_eq!(
        diagnostics[0]["range"]["end"],
        json!({"line": 2, "character": 18})
    );
    assert!(diagnostics[0]["message"]
        .as_str()
        .unwrap()
        .contains("help: did you mean `arm`?"));

    // The quick fix the help suggests.
    let range = json!({"start": {"line": 2, "character": 16}, "end": {"line": 2, "character": 16}});
    let actions = client.request(
        "textDocument/codeAction",
        json!({"textDocument": document, "range": range, "context": {"diagnostics": []}}),
    );
    let edit = &actions[0]["edit"]["changes"][&uri][0];
    assert_eq!(edit["newText"], "arm");
    assert_eq!(edit["range"]["start"], json!({"line": 2, "character": 15}));

    // Fixed: no diagnostics left.
    client.notify(
        "textDocument/didChange",
        json!({"textDocument": {"uri": uri, "version": 2}, "contentChanges": [{"text": FIXED}]}),
    );
    assert_eq!(client.diagnostics(), json!([]));

    // Hover: a body's mass properties; a join's coordinates.
    let hover = client.request(
        "textDocument/hover",
        json!({"textDocument": document, "position": position(FIXED, "arm with", 1)}),
    );
    let text = hover["contents"]["value"].as_str().expect("markdown");
    assert!(
        text.contains("value `arm`: body") && text.contains("mass: 2"),
        "{text}"
    );
    let hover = client.request(
        "textDocument/hover",
        json!({"textDocument": document, "position": position(FIXED, "shoulder.q", 2)}),
    );
    assert!(hover["contents"]["value"]
        .as_str()
        .unwrap()
        .contains("coordinates: `shoulder.q`"));

    // Definition in the standard library: `revolute` in joints.lsd, on the line that declares it.
    let definition = client.request(
        "textDocument/definition",
        json!({"textDocument": document, "position": position(FIXED, "revolute", 3)}),
    );
    let target = definition["uri"].as_str().expect("a location");
    assert!(target.ends_with("/joints.lsd"), "{target}");
    let joints = include_str!("../../stdlib/joints.lsd");
    let line = joints
        .lines()
        .position(|l| l.starts_with("let revolute("))
        .expect("declared");
    assert_eq!(
        definition["range"]["start"],
        json!({"line": line, "character": 4})
    );

    // References: the declaration and both uses.
    let references = client.request("textDocument/references", json!({"textDocument": document, "position": position(FIXED, "arm =", 0), "context": {"includeDeclaration": true}}));
    assert_eq!(references.as_array().map(Vec::len), Some(2));

    // Completion: a body's fields after `.`, the standard library after `import`.
    let typing = format!("{FIXED}apply force value = [0, 0, arm.");
    client.notify(
        "textDocument/didChange",
        json!({"textDocument": {"uri": uri, "version": 3}, "contentChanges": [{"text": typing}]}),
    );
    assert_eq!(client.diagnostics()[0]["code"], "E0202");
    let end = json!({"line": 4, "character": typing.lines().last().unwrap().len()});
    let items = client.request(
        "textDocument/completion",
        json!({"textDocument": document, "position": end}),
    );
    assert_eq!(labels(&items), ["frame", "iframe", "mass", "inertia"]);
    let typing = format!("import \n{FIXED}");
    client.notify(
        "textDocument/didChange",
        json!({"textDocument": {"uri": uri, "version": 4}, "contentChanges": [{"text": typing}]}),
    );
    client.diagnostics();
    let items = client.request(
        "textDocument/completion",
        json!({"textDocument": document, "position": {"line": 0, "character": 7}}),
    );
    let modules = labels(&items);
    assert!(
        modules.contains(&"joints") && modules.contains(&"gravity"),
        "{modules:?}"
    );

    // Formatting, symbols, semantic tokens and rename on the fixed program.
    client.notify(
        "textDocument/didChange",
        json!({"textDocument": {"uri": uri, "version": 5}, "contentChanges": [{"text": FIXED}]}),
    );
    client.diagnostics();
    let edits = client.request(
        "textDocument/formatting",
        json!({"textDocument": document, "options": {"tabSize": 2, "insertSpaces": true}}),
    );
    assert_eq!(
        edits[0]["newText"].as_str(),
        Some(FIXED.replace("[0,1,0]", "[0, 1, 0]").as_str())
    );
    let symbols = client.request(
        "textDocument/documentSymbol",
        json!({"textDocument": document}),
    );
    let names: Vec<&str> = symbols
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|s| s["name"].as_str())
        .collect();
    assert_eq!(names, ["joints", "arm", "shoulder"]);
    let tokens = client.request(
        "textDocument/semanticTokens/full",
        json!({"textDocument": document}),
    );
    let (lexed, _) = lsdc::syntax::lexer::lex(lsdc::source::FileId(0), FIXED);
    assert_eq!(tokens["data"].as_array().unwrap().len(), 5 * lexed.len());
    let renamed = client.request("textDocument/rename", json!({"textDocument": document, "position": position(FIXED, "arm =", 0), "newName": "upper_arm"}));
    assert_eq!(renamed["changes"][&uri].as_array().map(Vec::len), Some(2));

    client.request("shutdown", Value::Null);
    client.notify("exit", Value::Null);
    assert!(client.server.wait().expect("exits").success());
}
