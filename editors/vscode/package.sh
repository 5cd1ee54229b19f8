#!/bin/sh
# Packages the VS Code extension as a .vsix: installs the locked npm dependencies
# (package-lock.json: vscode-languageclient, and @vscode/vsce to package) when node_modules/ does
# not hold them yet, then runs vsce. Once node_modules/ is filled (or npm's cache holds the
# packages: `--offline`), no network is needed.
#
#   editors/vscode/package.sh [--offline] [OUTPUT_DIR]
#
# Writes OUTPUT_DIR/lsd-language-VERSION.vsix (OUTPUT_DIR: editors/vscode/ by default).
set -eu
cd "$(dirname "$0")"
offline=""
if [ "${1:-}" = "--offline" ]; then
    offline="--offline"
    shift
fi
out_dir="${1:-.}"
for tool in node npm; do
    command -v "$tool" >/dev/null || { echo "package.sh: \`$tool\` is not installed" >&2; exit 3; }
done
# npm records what it installed in node_modules/.package-lock.json: reinstall when the lock
# file differs from it or is newer.
if [ ! -f node_modules/.package-lock.json ] || [ package-lock.json -nt node_modules/.package-lock.json ]; then
    npm ci --no-audit --no-fund --prefer-offline $offline
fi
version=$(node -p 'require("./package.json").version')
mkdir -p "$out_dir"
out="$(cd "$out_dir" && pwd)/lsd-language-$version.vsix"
node node_modules/@vscode/vsce/vsce package --allow-missing-repository --skip-license --out "$out"
echo "$out"
