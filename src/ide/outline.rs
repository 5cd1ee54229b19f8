//! The file's outline (document symbols) and the classification of its tokens (semantic
//! tokens).

use lsp_types::{
    DocumentSymbol, SemanticToken, SemanticTokenModifier, SemanticTokenType, SemanticTokensLegend,
    SymbolKind,
};

use crate::check::types::Ty;
use crate::ide::analysis::{Analysis, DefinitionKind, Reference};
use crate::ide::convert;
use crate::source::Span;
use crate::syntax::ast::{Decl, DeclKind, ImportTarget};
use crate::syntax::lexer::{comments_in_gap, lex, Tok};

/// The bodies, links, joins, definitions, value inputs, packages and imports of the file.
pub fn document_symbols(analysis: &Analysis) -> Vec<DocumentSymbol> {
    let workspace = &analysis.compilation.workspace;
    let root = workspace.module(workspace.roots[0]);
    decl_symbols(analysis, &root.program.decls)
}

fn decl_symbols(analysis: &Analysis, decls: &[Decl]) -> Vec<DocumentSymbol> {
    let mut symbols = Vec::new();
    for decl in decls {
        match &decl.kind {
            DeclKind::Let(bindings) => {
                for binding in bindings {
                    let ty = type_of(analysis, binding.name.span);
                    let kind = match ty {
                        Some(Ty::Body) => SymbolKind::OBJECT,
                        Some(Ty::Link) => SymbolKind::STRUCT,
                        Some(Ty::Force | Ty::Torque) => SymbolKind::EVENT,
                        _ => SymbolKind::CONSTANT,
                    };
                    let detail = ty.map(|t| t.to_string());
                    symbols.push(symbol(
                        analysis,
                        &binding.name.name,
                        detail,
                        kind,
                        decl.span,
                        binding.name.span,
                        None,
                    ));
                }
            }
            DeclKind::Define(define) => symbols.push(symbol(
                analysis,
                &define.name.name,
                Some("parameterised definition".into()),
                SymbolKind::FUNCTION,
                decl.span,
                define.name.span,
                None,
            )),
            DeclKind::Join(join) => {
                let text = analysis.text(analysis.root);
                let name = match &join.name {
                    Some(name) => name.name.to_string(),
                    None => format!(
                        "join {} and {}",
                        &text[join.first.span.range()],
                        &text[join.second.span.range()]
                    ),
                };
                let selection = join.name.as_ref().map_or(join.first.span, |n| n.span);
                symbols.push(symbol(
                    analysis,
                    &name,
                    Some("join".into()),
                    SymbolKind::INTERFACE,
                    decl.span,
                    selection,
                    None,
                ));
            }
            DeclKind::Package(package) => {
                let children = decl_symbols(analysis, &package.decls);
                symbols.push(symbol(
                    analysis,
                    &package.name.name,
                    Some("package".into()),
                    SymbolKind::NAMESPACE,
                    decl.span,
                    package.name.span,
                    Some(children),
                ));
            }
            DeclKind::Import(import) => {
                let (name, span) = match &import.target {
                    ImportTarget::Module(ident) => (ident.name.to_string(), ident.span),
                    ImportTarget::Path { path, span } => (path.clone(), *span),
                };
                symbols.push(symbol(
                    analysis,
                    &name,
                    Some("import".into()),
                    SymbolKind::MODULE,
                    decl.span,
                    span,
                    None,
                ));
            }
            DeclKind::Drive(drive) => {
                if let Some(name) = drive.value_input_name() {
                    symbols.push(symbol(
                        analysis,
                        &name.name,
                        Some("input".into()),
                        SymbolKind::VARIABLE,
                        decl.span,
                        name.span,
                        None,
                    ));
                }
            }
            _ => {}
        }
    }
    symbols
}

fn type_of(analysis: &Analysis, name: Span) -> Option<Ty> {
    let occurrence = analysis
        .index
        .occurrence_at(name.file(), name.start() as usize)?;
    match occurrence.reference {
        Reference::Definition(id) => analysis.index.definitions[id].ty,
        _ => None,
    }
}

#[allow(deprecated)] // `DocumentSymbol::deprecated` must be given, though deprecated.
fn symbol(
    analysis: &Analysis,
    name: &str,
    detail: Option<String>,
    kind: SymbolKind,
    extent: Span,
    selection: Span,
    children: Option<Vec<DocumentSymbol>>,
) -> DocumentSymbol {
    DocumentSymbol {
        name: name.to_string(),
        detail,
        kind,
        tags: None,
        deprecated: None,
        range: convert::span_range(analysis, extent),
        selection_range: convert::span_range(analysis, selection),
        children,
    }
}

/// The token types of the legend, in the order their indices refer to.
const TOKEN_TYPES: [SemanticTokenType; 11] = [
    SemanticTokenType::NAMESPACE,
    SemanticTokenType::TYPE,
    SemanticTokenType::FUNCTION,
    SemanticTokenType::PARAMETER,
    SemanticTokenType::VARIABLE,
    SemanticTokenType::PROPERTY,
    SemanticTokenType::KEYWORD,
    SemanticTokenType::COMMENT,
    SemanticTokenType::STRING,
    SemanticTokenType::NUMBER,
    SemanticTokenType::OPERATOR,
];

#[derive(Clone, Copy)]
enum TokenType {
    Namespace,
    Type,
    Function,
    Parameter,
    Variable,
    Property,
    Keyword,
    Comment,
    String,
    Number,
    Operator,
}

const DECLARATION: u32 = 1;
const DEFAULT_LIBRARY: u32 = 2;

pub fn legend() -> SemanticTokensLegend {
    SemanticTokensLegend {
        token_types: TOKEN_TYPES.to_vec(),
        token_modifiers: vec![
            SemanticTokenModifier::DECLARATION,
            SemanticTokenModifier::DEFAULT_LIBRARY,
        ],
    }
}

/// Every token and comment of the root file, classified, in the protocol's relative encoding.
pub fn semantic_tokens(analysis: &Analysis) -> Vec<SemanticToken> {
    let text = analysis.text(analysis.root);
    let (tokens, _) = lex(analysis.root, text);
    let mut classified = Vec::with_capacity(tokens.len());
    let mut previous_end = 0;
    for (index, &(start, token, end)) in tokens.iter().enumerate() {
        for comment in comments_in_gap(&text[previous_end..start]) {
            classified.push((
                previous_end + comment.start,
                previous_end + comment.end,
                TokenType::Comment,
                0,
            ));
        }
        previous_end = end;
        let previous = index.checked_sub(1).map(|i| tokens[i].1);
        let next = tokens.get(index + 1).map(|t| t.1);
        let (kind, modifiers) = classify(analysis, start, token, previous, next);
        classified.push((start, end, kind, modifiers));
    }
    for comment in comments_in_gap(&text[previous_end..]) {
        classified.push((
            previous_end + comment.start,
            previous_end + comment.end,
            TokenType::Comment,
            0,
        ));
    }
    encode(text, &classified)
}

fn classify(
    analysis: &Analysis,
    start: usize,
    token: Tok<'_>,
    previous: Option<Tok<'_>>,
    next: Option<Tok<'_>>,
) -> (TokenType, u32) {
    match token {
        Tok::Ident(_) => identifier(analysis, start),
        Tok::Unknown(_) => (TokenType::Variable, 0),
        Tok::Int(_) | Tok::Float(_) => (TokenType::Number, 0),
        Tok::Str(_) | Tok::UnterminatedStr => (TokenType::String, 0),
        Tok::Body | Tok::Force | Tok::Torque
            if previous == Some(Tok::Dot) || next == Some(Tok::Equal) =>
        {
            (TokenType::Property, 0)
        }
        token if token.text().chars().all(char::is_alphabetic) => (TokenType::Keyword, 0),
        _ => (TokenType::Operator, 0),
    }
}

fn identifier(analysis: &Analysis, start: usize) -> (TokenType, u32) {
    let Some(occurrence) = analysis.index.occurrence_at(analysis.root, start) else {
        return (TokenType::Variable, 0);
    };
    match occurrence.reference {
        Reference::Definition(id) => {
            let definition = &analysis.index.definitions[id];
            let declaration = if definition.span == occurrence.span {
                DECLARATION
            } else {
                0
            };
            let kind = match definition.kind {
                DefinitionKind::Function { .. } => TokenType::Function,
                DefinitionKind::Package(_) | DefinitionKind::Module(_) => TokenType::Namespace,
                DefinitionKind::Parameter | DefinitionKind::Coordinate => TokenType::Parameter,
                DefinitionKind::Value
                | DefinitionKind::Join
                | DefinitionKind::Local
                | DefinitionKind::Input => TokenType::Variable,
            };
            (kind, declaration)
        }
        Reference::Builtin => {
            let text = &analysis.text(analysis.root)[occurrence.span.range()];
            let kind = if Ty::from_annotation(text).is_some() {
                TokenType::Type
            } else if crate::check::types::is_builtin_function(text) {
                TokenType::Function
            } else {
                TokenType::Variable
            };
            (kind, DEFAULT_LIBRARY)
        }
        Reference::Field => (TokenType::Property, 0),
        Reference::Unresolved => (TokenType::Variable, 0),
    }
}

/// The protocol's encoding: each token relative to the previous one, one line at a time (a
/// comment over several lines is one token per line).
fn encode(text: &str, classified: &[(usize, usize, TokenType, u32)]) -> Vec<SemanticToken> {
    let lines = convert::LineStarts::new(text);
    let mut encoded = Vec::with_capacity(classified.len());
    let (mut last_line, mut last_start) = (0, 0);
    for &(start, end, kind, modifiers) in classified {
        let mut line_start = start;
        for piece in text[start..end].split('\n') {
            let position = lines.position(text, line_start);
            let length: usize = piece.chars().map(char::len_utf16).sum();
            line_start += piece.len() + 1;
            if length == 0 {
                continue;
            }
            let delta_line = position.line - last_line;
            let delta_start = if delta_line == 0 {
                position.character - last_start
            } else {
                position.character
            };
            encoded.push(SemanticToken {
                delta_line,
                delta_start,
                length: length as u32,
                token_type: kind as u32,
                token_modifiers_bitset: modifiers,
            });
            (last_line, last_start) = (position.line, position.character);
        }
    }
    encoded
}
