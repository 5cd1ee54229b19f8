// Starts `lsdc lsp` for LSD files and test manifests (`lsdtest.toml`, where it completes scene
// names) and connects VS Code to it over standard input and output.
const vscode = require("vscode");
const { LanguageClient } = require("vscode-languageclient/node");

let client;

function activate(context) {
  const settings = vscode.workspace.getConfiguration("lsd.server");
  const env = { ...process.env };
  const libraryPath = settings.get("libraryPath");
  if (libraryPath) {
    env.LSD_PATH = env.LSD_PATH ? `${libraryPath}:${env.LSD_PATH}` : libraryPath;
  }
  const server = { command: settings.get("path") || "lsdc", args: ["lsp"], options: { env } };
  client = new LanguageClient(
    "lsd",
    "LSD language server",
    { run: server, debug: server },
    {
      documentSelector: [
        { scheme: "file", language: "lsd" },
        { scheme: "file", pattern: "**/lsdtest.toml" },
      ],
    }
  );
  context.subscriptions.push(client);
  return client.start();
}

function deactivate() {
  return client ? client.stop() : undefined;
}

module.exports = { activate, deactivate };
