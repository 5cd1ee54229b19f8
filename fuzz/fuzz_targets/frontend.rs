//! Feeds arbitrary text to the whole front end (lexer, parser, imports of the standard library,
//! checker, elaborator, diagnostic rendering): none of it may panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use lsdc::load::LoadOptions;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = lsdc::driver::compile_text("fuzz.lsd", text, None, &options);
    let _ = lsdc::diag::render::to_text(&compilation.workspace.sources, &compilation.diagnostics);
    let _ =
        lsdc::diag::render::to_json_value(&compilation.workspace.sources, &compilation.diagnostics);
    if let Some(mechanism) = &compilation.mechanism {
        let _ = mechanism.summary();
        let _ = mechanism.dump();
    }
});
