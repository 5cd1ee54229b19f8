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
            let read = self.output.read_line(&mut line).expect("reads a header");
            assert!(read > 0, "the server closed its output");
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
        self.response(method, params)["result"].clone()
    }

    /// The whole response to a request: its `result` or its `error`.
    fn response(&mut self, method: &str, params: Value) -> Value {
        self.next_id += 1;
        let id = self.next_id;
        self.send(json!({"jsonrpc": "2.0", "id": id, "method": method, "params": params}));
        loop {
            let message = self.receive();
            if message["id"] == id {
                return message;
            }
            self.notifications.push(message);
        }
    }

    fn notify(&mut self, method: &str, params: Value) {
        self.send(json!({"jsonrpc": "2.0", "method": method, "params": params}));
    }

    fn initialize(&mut self) {
        self.request("initialize", json!({"capabilities": {}}));
        self.notify("initialized", json!({}));
    }

    fn stop(mut self) {
        self.request("shutdown", Value::Null);
        self.notify("exit", Value::Null);
        assert!(self.server.wait().expect("exits").success());
    }

    fn open(&mut self, uri: &str, text: &str) -> Value {
        self.notify(
            "textDocument/didOpen",
            json!({"textDocument": {"uri": uri, "languageId": "lsd", "version": 1, "text": text}}),
        );
        self.diagnostics()
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
    assert_eq!(initialized["serverInfo"]["name"], "lsdc");
    assert_eq!(
        initialized["serverInfo"]["version"],
        env!("CARGO_PKG_VERSION")
    );
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
    assert_eq!(actions[0]["title"], "replace `arn` by `arm`");
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

    client.stop();
}

/// A library and two programs that import it, in a directory of their own.
const LIBRARY: &str = "(* The arm's length, in metres. *)\nlet L = 0.25 * 4 + 0.5 ;\n";
const USER_A: &str = "import parts ;\nimport joints ;\nlet arm = body mass = L end ;\n\
    join earth and arm with revolute([0, 0, 1]) ;\n";
const USER_B: &str = "import parts ;\nlet b = body mass = 2 * L end ;\n";

#[test]
fn values_on_hover_references_and_rename_across_libraries() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("lsp_across");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("a directory");
    for (name, text) in [
        ("parts.lsd", LIBRARY),
        ("user_a.lsd", USER_A),
        ("user_b.lsd", USER_B),
    ] {
        std::fs::write(dir.join(name), text).expect("written");
    }
    let dir = std::fs::canonicalize(&dir).expect("canonical");
    let [library, user_a, user_b] =
        ["parts.lsd", "user_a.lsd", "user_b.lsd"].map(|name| file_uri(&dir.join(name)));
    let mut client = Client::start();
    client.initialize();
    // Only `user_a.lsd` is open: the library and `user_b.lsd` are read from disk.
    assert_eq!(client.open(&user_a, USER_A), json!([]));
    let document = json!({"uri": user_a});
    let at_length = json!({"textDocument": document, "position": position(USER_A, "L end", 0)});

    // Hover: the constant's value (0.25 * 4 + 0.5), its type and its documentation.
    let hover = client.request("textDocument/hover", at_length.clone());
    let text = hover["contents"]["value"].as_str().expect("markdown");
    assert!(text.contains("value `L`: scalar = 1.5"), "{text}");
    assert!(text.contains("The arm's length, in metres."), "{text}");

    // References: the definition in the library and the uses in both programs.
    let mut with_declaration = at_length.clone();
    with_declaration["context"] = json!({"includeDeclaration": true});
    let references = client.request("textDocument/references", with_declaration);
    let mut files: Vec<&str> = (references.as_array().expect("locations").iter())
        .map(|l| l["uri"].as_str().expect("a URI"))
        .collect();
    files.sort();
    assert_eq!(files, [library.as_str(), user_a.as_str(), user_b.as_str()]);

    // Rename: one edit in each file, at the name.
    let mut renaming = at_length.clone();
    renaming["newName"] = json!("arm_length");
    let edit = client.request("textDocument/rename", renaming);
    for (uri, text, needle) in [
        (&library, LIBRARY, "L ="),
        (&user_a, USER_A, "L end"),
        (&user_b, USER_B, "L end"),
    ] {
        let edits = edit["changes"][uri].as_array().expect("edits in each file");
        assert_eq!(edits.len(), 1, "{uri}: {edits:?}");
        assert_eq!(edits[0]["newText"], "arm_length");
        assert_eq!(edits[0]["range"]["start"], position(text, needle, 0));
    }

    // The standard library's names are not renamed.
    let refused = client.response("textDocument/rename", json!({"textDocument": document, "position": position(USER_A, "revolute", 0), "newName": "hinge"}));
    let message = refused["error"]["message"].as_str().expect("an error");
    assert!(message.contains("standard library (`joints`)"), "{message}");
    client.stop();
}

#[test]
fn quick_fixes_are_the_fixes_the_diagnostics_carry() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples/quick_fix.lsd");
    let uri = file_uri(&path);
    let mut client = Client::start();
    client.initialize();
    // `revolute` without `import joints`, and a `//` comment.
    let text =
        "// an arm\nlet arm = body mass = 1 end ;\njoin earth and arm with revolute([0, 0, 1]) ;\n";
    let diagnostics = client.open(&uri, text);
    assert_eq!(diagnostics[0]["code"], "E0104", "{diagnostics}");
    let everywhere =
        json!({"start": {"line": 0, "character": 0}, "end": {"line": 3, "character": 0}});
    let actions = client.request(
        "textDocument/codeAction",
        json!({"textDocument": {"uri": uri}, "range": everywhere, "context": {"diagnostics": []}}),
    );
    let titles: Vec<&str> = (actions.as_array().expect("actions").iter())
        .map(|a| a["title"].as_str().expect("a title"))
        .collect();
    assert_eq!(titles, ["replace `// an arm` by `(* an arm *)`"]);
    let edit = &actions[0]["edit"]["changes"][&uri][0];
    assert_eq!(edit["newText"], "(* an arm *)");

    // Once the comment is fixed, the checker's error and its fix: the missing import.
    let text = text.replacen("// an arm", "(* an arm *)", 1);
    client.notify(
        "textDocument/didChange",
        json!({"textDocument": {"uri": uri, "version": 2}, "contentChanges": [{"text": text}]}),
    );
    assert_eq!(client.diagnostics()[0]["code"], "E0301");
    let actions = client.request(
        "textDocument/codeAction",
        json!({"textDocument": {"uri": uri}, "range": everywhere, "context": {"diagnostics": []}}),
    );
    assert_eq!(
        actions[0]["title"],
        "insert the line `import joints ;` before line 2"
    );
    let edit = &actions[0]["edit"]["changes"][&uri][0];
    assert_eq!(edit["newText"], "import joints ;\n");
    assert_eq!(edit["range"]["start"], json!({"line": 1, "character": 0}));
    client.stop();
}

/// A program with a package and an array of packages, for completion after their names.
const PACKAGES: &str = "import joints ;
package Arm =
  let upper = body mass = 1, iframe = 1, inertia = [0.1, 0.1, 0.1] end ;
  join earth and upper with revolute([1, 0, 0]) as sh ;
end ;
package leg[i in 1 .. 2] =
  let thigh = body mass = 1, iframe = 1, inertia = [0.1, 0.1, 0.1] end ;
  join earth and thigh with revolute([0, 1, 0]) as knee ;
end ;
";

#[test]
fn completion_after_a_package_member_and_an_instance() {
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("lsp_packages.lsd");
    let uri = file_uri(&path);
    let mut client = Client::start();
    let initialized = client.request("initialize", json!({"capabilities": {}}));
    assert_eq!(initialized["serverInfo"]["name"], "lsdc");
    client.notify("initialized", json!({}));
    assert_eq!(client.open(&uri, PACKAGES), json!([]));
    let mut version = 1;
    let mut complete = |client: &mut Client, typed: &str| {
        version += 1;
        let text = format!("{PACKAGES}output o = {typed}");
        client.notify(
            "textDocument/didChange",
            json!({"textDocument": {"uri": uri, "version": version}, "contentChanges": [{"text": text}]}),
        );
        client.diagnostics();
        let end = json!({"line": PACKAGES.lines().count(), "character": text.lines().last().unwrap().len()});
        let items = client.request(
            "textDocument/completion",
            json!({"textDocument": {"uri": uri}, "position": end}),
        );
        let mut labels: Vec<String> = labels(&items).iter().map(|l| l.to_string()).collect();
        labels.sort();
        labels
    };
    // The index is a member too: `leg[1]:i` is 1.
    assert_eq!(complete(&mut client, "leg[1]:"), ["i", "knee", "thigh"]);
    assert_eq!(complete(&mut client, "Arm:"), ["sh", "upper"]);
    assert_eq!(complete(&mut client, "Arm:sh."), ["q"]);
    assert_eq!(complete(&mut client, "leg[1]:knee."), ["q"]);
    assert_eq!(
        complete(&mut client, "leg[2]:thigh."),
        ["frame", "iframe", "inertia", "mass"]
    );
    client.stop();
}

/// Hover on a join of a package and of an array of packages, where a program reads it: the
/// coordinates of the instance named (`leg[1]:knee.q`), as for a join of the main program.
#[test]
fn hover_on_an_instances_join_lists_its_coordinates() {
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("lsp_instance_hover.lsd");
    let uri = file_uri(&path);
    let text = format!("{PACKAGES}output o = leg[1]:knee.q ;\noutput p = Arm:sh.q ;\n");
    let mut client = Client::start();
    client.initialize();
    assert_eq!(client.open(&uri, &text), json!([]));
    let hover = |client: &mut Client, at: &str| {
        let found = client.request(
            "textDocument/hover",
            json!({"textDocument": {"uri": uri}, "position": position(&text, at, 0)}),
        );
        found["contents"]["value"]
            .as_str()
            .unwrap_or_else(|| panic!("a hover at `{at}`: {found}"))
            .to_string()
    };
    let knee = hover(&mut client, "knee.q");
    assert!(knee.contains("coordinates: `leg[1]:knee.q`"), "{knee}");
    // At the declaration, every instance's.
    let declared = hover(&mut client, "knee ;");
    assert!(
        declared.contains("coordinates: `leg[1]:knee.q`, `leg[2]:knee.q`"),
        "{declared}"
    );
    let sh = hover(&mut client, "sh.q");
    assert!(sh.contains("coordinates: `sh.q`"), "{sh}");
    client.stop();
}

/// Completion of scene names in a test manifest (`lsdtest.toml`), where a case names the scene
/// its program runs: inside `scene = "`, the scenes of the case's `program`, read from the
/// editor when it is open there (its text not saved), else from disk; nothing elsewhere in the
/// manifest, which the server reads without LSD diagnostics.
#[test]
fn completion_of_scene_names_in_a_test_manifest() {
    let folder = PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let cell = std::fs::canonicalize("examples/robot_cell.lsd").expect("the example");
    let program = folder.join("lsp_scenes_unsaved.lsd");
    let program_text = "import joints ;
let b = body mass = 1, iframe = 1, inertia = [0.1, 0.1, 0.1] end ;
join earth and b with revolute([0, 0, 1]) as pivot ;
scene swing = output angle = pivot.q ; end ;
scene held = lock pivot.q = 0.2 ; end ;
";
    let manifest = format!(
        "[defaults]\nrelative = 1e-8\n\n[[case]]\nname = \"cell\"\nprogram = \"{}\" # on disk\nscene = \"le\n\n[[case]]\nname = \"unsaved\"\nscene = \"\nprogram = \"lsp_scenes_unsaved.lsd\"\n",
        cell.display()
    );
    let mut client = Client::start();
    client.initialize();
    assert_eq!(client.open(&file_uri(&program), program_text), json!([]));
    let uri = file_uri(&folder.join("lsdtest.toml"));
    client.notify(
        "textDocument/didOpen",
        json!({"textDocument": {"uri": uri, "languageId": "toml", "version": 1, "text": manifest}}),
    );
    let complete = |client: &mut Client, needle: &str, skip: usize| {
        let at = position(&manifest, needle, skip);
        let items = client.request(
            "textDocument/completion",
            json!({"textDocument": {"uri": uri}, "position": at}),
        );
        labels(&items)
            .iter()
            .map(|l| l.to_string())
            .collect::<Vec<_>>()
    };
    assert_eq!(
        complete(&mut client, "scene = \"le", 11),
        [
            "left_trajectory",
            "right_statics",
            "linkage_check",
            "cell",
            "left_weightless"
        ]
    );
    assert_eq!(complete(&mut client, "scene = \"\n", 9), ["swing", "held"]);
    // Not in a scene's value: the case's name, the program's path, the defaults.
    assert!(complete(&mut client, "name = \"cell", 12).is_empty());
    assert!(complete(&mut client, "# on disk", 0).is_empty());
    assert!(complete(&mut client, "relative", 3).is_empty());
    client.stop();
}

/// A value input (`input voltage = 12`) is a name like a `let`'s: hover says what it is and how
/// it is set, go-to-definition and references find its declaration and its reads, completion
/// offers it, and the outline lists it.
#[test]
fn a_value_input_is_a_name_the_editor_knows() {
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("lsp_value_input.lsd");
    let uri = file_uri(&path);
    let text = "import joints ;
let arm = body mass = 1, iframe = 1, inertia = [0.1, 0.1, 0.1] end ;
join earth and arm with revolute([0, 0, 1]) as pivot ;
input voltage = 12 ;
apply torque value = [0, 0, 0.1 * voltage], body = earth end on arm ;
output u = voltage ;
";
    let mut client = Client::start();
    client.initialize();
    assert_eq!(client.open(&uri, text), json!([]));
    let document = json!({"uri": uri});

    let hover = client.request(
        "textDocument/hover",
        json!({"textDocument": document, "position": position(text, "voltage], body", 2)}),
    );
    let hover = hover["contents"]["value"].as_str().expect("a hover");
    assert!(hover.contains("input `voltage`"), "{hover}");
    assert!(hover.contains("input voltage = 12"), "{hover}");

    let definition = client.request(
        "textDocument/definition",
        json!({"textDocument": document, "position": position(text, "voltage ;\n", 0)}),
    );
    assert_eq!(
        definition["range"]["start"],
        position(text, "voltage = 12", 0)
    );
    let references = client.request("textDocument/references", json!({"textDocument": document, "position": position(text, "voltage = 12", 0), "context": {"includeDeclaration": true}}));
    assert_eq!(references.as_array().map(Vec::len), Some(3), "{references}");

    let typing = format!("{text}output w = vol");
    client.notify(
        "textDocument/didChange",
        json!({"textDocument": {"uri": uri, "version": 2}, "contentChanges": [{"text": typing}]}),
    );
    client.diagnostics();
    let end = json!({"line": 6, "character": "output w = vol".len()});
    let items = client.request(
        "textDocument/completion",
        json!({"textDocument": document, "position": end}),
    );
    assert!(labels(&items).contains(&"voltage"), "{items}");

    client.notify(
        "textDocument/didChange",
        json!({"textDocument": {"uri": uri, "version": 3}, "contentChanges": [{"text": text}]}),
    );
    client.diagnostics();
    let symbols = client.request(
        "textDocument/documentSymbol",
        json!({"textDocument": document}),
    );
    let names: Vec<&str> = (symbols.as_array().expect("symbols").iter())
        .filter_map(|s| s["name"].as_str())
        .collect();
    assert_eq!(names, ["joints", "arm", "pivot", "voltage"]);
    client.stop();
}
