//! Loading a program and its libraries: parse the root files, follow `import` declarations along
//! the search path (the importing file's directory, `-L` directories, `LSD_PATH`, then the
//! standard library embedded in the binary), detect import cycles and missing files.

pub mod scene;
pub mod stdlib;
pub mod urdf;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use crate::diag::{suggest, Diagnostic, Diagnostics};
use crate::source::SourceMap;
use crate::source::{FileId, Span};
use crate::syntax::ast::{Decl, DeclKind, ImportTarget, Program};
use crate::syntax::parser::parse;
use urdf::{import_urdf_at, ImportOptions};

/// Environment variable holding extra library directories, separated by `:`.
pub const PATH_VARIABLE: &str = "LSD_PATH";

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ModuleId(pub u32);

pub struct Module {
    pub file: FileId,
    pub program: Program,
    /// The name a plain `import` gives this module (`joints` for `joints.lsd`).
    pub name: String,
    /// Directory imports are resolved against; `None` for the embedded standard library.
    dir: Option<PathBuf>,
    /// The import declaration that first brought this module in (`None` for root files).
    pub imported_at: Option<(Span, ModuleId)>,
}

/// Every module of a compilation, and for each `import` declaration the module it names.
pub struct Workspace {
    pub sources: SourceMap,
    pub modules: Vec<Module>,
    pub roots: Vec<ModuleId>,
    pub imports: HashMap<Span, ModuleId>,
    /// The scenes of the root programs and the one selected (`scene::select`).
    pub scenes: scene::Scenes,
}

impl Workspace {
    pub fn module(&self, id: ModuleId) -> &Module {
        &self.modules[id.0 as usize]
    }

    /// Adds "imported here" labels to diagnostics located in libraries, so an error in a library
    /// is shown both where it is and where the user's program brought the library in.
    pub fn add_import_context(&self, diagnostic: &mut Diagnostic) {
        let Some(span) = diagnostic.primary_span() else {
            return;
        };
        let mut module = self.modules.iter().position(|m| m.file == span.file());
        let mut hops = 0;
        while let Some(index) = module {
            let Some((site, importer)) = self.modules[index].imported_at else {
                break;
            };
            let name = &self.modules[index].name;
            if !diagnostic.labels.iter().any(|l| l.span == site) {
                diagnostic.labels.push(crate::diag::Label {
                    span: site,
                    message: format!("`{name}` imported here"),
                    primary: false,
                });
            }
            module = Some(importer.0 as usize);
            hops += 1;
            if hops > self.modules.len() {
                break;
            }
        }
    }
}

/// A root file that cannot be read (imports that cannot be read are diagnostics of the
/// importing program instead).
#[derive(Debug)]
pub struct LoadError {
    pub path: PathBuf,
    pub error: std::io::Error,
}

impl std::fmt::Display for LoadError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "cannot read `{}`: {}", self.path.display(), self.error)
    }
}

impl std::error::Error for LoadError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&self.error)
    }
}

pub struct LoadOptions {
    /// `-L` directories, searched after the importing file's directory.
    pub library_dirs: Vec<PathBuf>,
    /// Also search the directories of `LSD_PATH`.
    pub use_environment: bool,
    /// The scene to select in the root programs (`--scene`); `None`: the first each declares.
    pub scene: Option<String>,
}

impl Default for LoadOptions {
    fn default() -> Self {
        LoadOptions {
            library_dirs: Vec::new(),
            use_environment: true,
            scene: None,
        }
    }
}

/// Where a module's text comes from; also the key that makes a library load once.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
enum Origin {
    File(PathBuf),
    Stdlib(&'static str),
    /// A root given as text (tests, `--expr`, fuzzing).
    Text(String),
}

struct Loader {
    search_dirs: Vec<PathBuf>,
    /// `LoadOptions::scene`.
    scene: Option<String>,
    workspace: Workspace,
    by_origin: HashMap<Origin, ModuleId>,
    /// Modules whose imports are being followed: an import of one of them is a cycle.
    in_progress: Vec<ModuleId>,
    diagnostics: Diagnostics,
}

/// Loads root files from disk and everything they import. A `.urdf` file is imported as the
/// LSD program `lsdc import-urdf` writes for it, with the default options.
pub fn load_files(
    paths: &[PathBuf],
    options: &LoadOptions,
) -> Result<(Workspace, Diagnostics), LoadError> {
    let mut loader = Loader::new(options);
    for path in paths {
        let text = read_source(path).map_err(|error| LoadError {
            path: path.clone(),
            error,
        })?;
        let key = path.canonicalize().unwrap_or_else(|_| path.clone());
        if is_urdf(path) {
            if let Some(id) = loader.add_urdf(Origin::File(key), path.display().to_string(), text) {
                loader.workspace.roots.push(id);
            }
            continue;
        }
        let dir = path.parent().map(|p| {
            if p.as_os_str().is_empty() {
                PathBuf::from(".")
            } else {
                p.to_path_buf()
            }
        });
        let id = loader.add_module(
            Origin::File(key),
            path.display().to_string(),
            text,
            dir,
            None,
        );
        loader.workspace.roots.push(id);
    }
    Ok(loader.finish())
}

/// The largest program text read, in bytes: far above any mechanism written or generated (a
/// chain of 10^6 bodies is about 210 MiB), and a bound on what an endless input (`/dev/zero`, a
/// pipe that never closes) can take before it is refused.
pub const MAX_SOURCE_BYTES: u64 = 1 << 30;

/// The text of a file, or of standard input for `-`, refused beyond `MAX_SOURCE_BYTES`.
pub fn read_source(path: &Path) -> std::io::Result<String> {
    if path == Path::new("-") {
        return read_bounded(std::io::stdin(), MAX_SOURCE_BYTES);
    }
    read_bounded(std::fs::File::open(path)?, MAX_SOURCE_BYTES)
}

/// All the text of `reader`, or an error once it goes on past `limit` bytes.
pub fn read_bounded(reader: impl std::io::Read, limit: u64) -> std::io::Result<String> {
    use std::io::Read;
    let mut text = String::new();
    reader.take(limit + 1).read_to_string(&mut text)?;
    if text.len() as u64 > limit {
        return Err(std::io::Error::new(
            std::io::ErrorKind::FileTooLarge,
            format!(
                "it is longer than {} bytes ({} MiB), the most a program may be",
                limit,
                limit >> 20
            ),
        ));
    }
    Ok(text)
}

fn is_urdf(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("urdf"))
}

/// Loads a program given as text (its imports are resolved against `dir`).
pub fn load_text(
    name: &str,
    text: &str,
    dir: Option<&Path>,
    options: &LoadOptions,
) -> (Workspace, Diagnostics) {
    let mut loader = Loader::new(options);
    let id = loader.add_module(
        Origin::Text(name.to_string()),
        name.to_string(),
        text.to_string(),
        dir.map(Path::to_path_buf),
        None,
    );
    loader.workspace.roots.push(id);
    loader.finish()
}

impl Loader {
    fn new(options: &LoadOptions) -> Loader {
        let mut search_dirs = options.library_dirs.clone();
        if options.use_environment {
            if let Some(value) = std::env::var_os(PATH_VARIABLE) {
                search_dirs
                    .extend(std::env::split_paths(&value).filter(|p| !p.as_os_str().is_empty()));
            }
        }
        Loader {
            search_dirs,
            scene: options.scene.clone(),
            workspace: Workspace {
                sources: SourceMap::new(),
                modules: Vec::new(),
                roots: Vec::new(),
                imports: HashMap::new(),
                scenes: scene::Scenes::default(),
            },
            by_origin: HashMap::new(),
            in_progress: Vec::new(),
            diagnostics: Diagnostics::default(),
        }
    }

    fn finish(self) -> (Workspace, Diagnostics) {
        (self.workspace, self.diagnostics)
    }

    fn add_module(
        &mut self,
        origin: Origin,
        display_name: String,
        text: String,
        dir: Option<PathBuf>,
        imported_at: Option<(Span, ModuleId)>,
    ) -> ModuleId {
        let file = self.workspace.sources.add(display_name, text);
        let (mut program, errors) = parse(file, &self.workspace.sources.file(file).text);
        for error in errors {
            self.diagnostics.push(error);
        }
        if imported_at.is_some() {
            scene::leave_out(&mut program);
        } else {
            let mut found = Vec::new();
            let scenes = scene::select(&mut program, self.scene.as_deref(), &mut found);
            found.into_iter().for_each(|d| self.diagnostics.push(d));
            if !scenes.names.is_empty() || self.scene.is_some() {
                self.workspace.scenes = scenes;
            }
        }
        let name = module_name(&origin);
        let id = ModuleId(self.workspace.modules.len() as u32);
        self.workspace.modules.push(Module {
            file,
            program: Program { decls: Vec::new() },
            name,
            dir,
            imported_at,
        });
        self.by_origin.insert(origin, id);
        self.in_progress.push(id);
        self.follow_imports(id, &program.decls);
        self.in_progress.pop();
        self.workspace.modules[id.0 as usize].program = program;
        id
    }

    /// A URDF root: its text joins the source map, so the import's diagnostics point into it,
    /// and the LSD program imported from it becomes the module. That program's imports are
    /// looked up on the search path and in the standard library, not beside the URDF file: it
    /// was written for the standard `joints` and `gravity`.
    fn add_urdf(&mut self, origin: Origin, display_name: String, xml: String) -> Option<ModuleId> {
        let file = self.workspace.sources.add(display_name.clone(), xml);
        let xml = &self.workspace.sources.file(file).text;
        match import_urdf_at(file, &display_name, xml, &ImportOptions::default()) {
            Ok(imported) => {
                for warning in imported.warnings {
                    self.diagnostics.push(warning);
                }
                Some(self.add_module(
                    origin,
                    format!("{display_name} (imported as LSD)"),
                    imported.text,
                    None,
                    None,
                ))
            }
            Err(error) => {
                self.diagnostics.push(error);
                None
            }
        }
    }

    fn follow_imports(&mut self, importer: ModuleId, decls: &[Decl]) {
        for decl in decls {
            match &decl.kind {
                DeclKind::Import(import) => {
                    if let Some(id) = self.resolve_import(importer, decl.span, &import.target) {
                        self.workspace.imports.insert(decl.span, id);
                    }
                }
                DeclKind::Package(package) => self.follow_imports(importer, &package.decls),
                _ => {}
            }
        }
    }

    fn resolve_import(
        &mut self,
        importer: ModuleId,
        site: Span,
        target: &ImportTarget,
    ) -> Option<ModuleId> {
        let (file_name, target_span) = match target {
            ImportTarget::Module(ident) => (format!("{}.lsd", ident.name), ident.span),
            ImportTarget::Path { path, span } => (path.clone(), *span),
        };
        let is_module_name = matches!(target, ImportTarget::Module(_));
        let Some((origin, text, display)) = self.find(importer, &file_name, is_module_name) else {
            self.diagnostics.push(self.missing_import(
                importer,
                &file_name,
                is_module_name,
                target_span,
            ));
            return None;
        };
        if let Some(&existing) = self.by_origin.get(&origin) {
            if let Some(position) = self.in_progress.iter().position(|&m| m == existing) {
                self.diagnostics
                    .push(self.cycle(&self.in_progress[position..], target_span));
                return None;
            }
            return Some(existing);
        }
        let dir = match &origin {
            Origin::File(_) => Path::new(&display).parent().map(Path::to_path_buf),
            Origin::Stdlib(_) | Origin::Text(_) => None,
        };
        Some(self.add_module(origin, display, text, dir, Some((site, importer))))
    }

    /// Finds an import: the importing file's directory, the search path, then (for module names)
    /// the standard library. The standard library's own imports stay inside it.
    fn find(
        &self,
        importer: ModuleId,
        file_name: &str,
        is_module_name: bool,
    ) -> Option<(Origin, String, String)> {
        let importer_dir = self.workspace.module(importer).dir.clone();
        let from_stdlib =
            importer_dir.is_none() && matches!(self.origin_of(importer), Some(Origin::Stdlib(_)));
        if !from_stdlib {
            let dirs = importer_dir.iter().chain(self.search_dirs.iter());
            for dir in dirs {
                let candidate = dir.join(file_name);
                if candidate.is_file() {
                    let text = read_source(&candidate).ok()?;
                    let display = candidate.display().to_string();
                    let canonical = candidate.canonicalize().unwrap_or(candidate);
                    return Some((Origin::File(canonical), text, display));
                }
            }
        }
        let stem = file_name.strip_suffix(".lsd").unwrap_or(file_name);
        if is_module_name || from_stdlib {
            if let Some((name, text)) = stdlib::find(stem) {
                return Some((
                    Origin::Stdlib(name),
                    text.to_string(),
                    format!("<stdlib>/{name}.lsd"),
                ));
            }
        }
        None
    }

    fn origin_of(&self, id: ModuleId) -> Option<&Origin> {
        self.by_origin
            .iter()
            .find(|(_, &m)| m == id)
            .map(|(o, _)| o)
    }

    fn missing_import(
        &self,
        importer: ModuleId,
        file_name: &str,
        is_module_name: bool,
        span: Span,
    ) -> Diagnostic {
        let mut searched: Vec<String> = self
            .workspace
            .module(importer)
            .dir
            .iter()
            .map(|d| d.display().to_string())
            .collect();
        searched.extend(self.search_dirs.iter().map(|d| d.display().to_string()));
        let stem = file_name.strip_suffix(".lsd").unwrap_or(file_name);
        let mut diagnostic =
            Diagnostic::error("E0501", format!("cannot find library `{file_name}`"))
                .primary(span, "no such file on the library search path")
                .note(match (is_module_name, searched.is_empty()) {
                    (true, true) => "searched: the standard library".to_string(),
                    (true, false) => format!(
                        "searched: {}, then the standard library",
                        searched.join(", ")
                    ),
                    (false, _) => format!("searched: {}", searched.join(", ")),
                });
        let mut known: Vec<&str> = stdlib::names().collect();
        known.sort();
        diagnostic = match suggest::did_you_mean(stem, known.iter().copied()) {
            Some(name) => diagnostic.help(format!("did you mean the standard library's `{name}`?")),
            None => diagnostic.help(format!(
                "add its directory with `-L DIR` or to `{PATH_VARIABLE}`; the standard library has: {}",
                known.join(", ")
            )),
        };
        diagnostic
    }

    fn cycle(&self, chain: &[ModuleId], span: Span) -> Diagnostic {
        let names: Vec<String> = chain
            .iter()
            .map(|&m| {
                self.workspace
                    .sources
                    .file(self.workspace.module(m).file)
                    .name
                    .clone()
            })
            .collect();
        let mut path = names.join(" → ");
        path.push_str(&format!(" → {}", names[0]));
        let mut diagnostic = Diagnostic::error("E0502", "import cycle")
            .primary(
                span,
                format!("this imports `{}`, which is still being loaded", names[0]),
            )
            .note(format!("the cycle: {path}"))
            .help("move the shared definitions into a library that both files import");
        for &module in chain.iter().skip(1) {
            if let Some((site, _)) = self.workspace.module(module).imported_at {
                diagnostic = diagnostic.secondary(site, "part of the cycle");
            }
        }
        diagnostic
    }
}

fn module_name(origin: &Origin) -> String {
    match origin {
        Origin::File(path) => path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        Origin::Stdlib(name) => name.to_string(),
        Origin::Text(name) => Path::new(name)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
    }
}
