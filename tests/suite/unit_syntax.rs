//! Unit tests of `src/syntax/`: the lexer and the parser.
//! Each module holds the tests of the file of `src/` it is named after, kept out of the library
//! so that `cargo test` compiles the library once (`test = false` in Cargo.toml).

mod lexer {
    use lsdc::source::FileId;
    use lsdc::syntax::lexer::*;

    fn tokens(text: &str) -> Vec<Tok<'_>> {
        let (tokens, errors) = lex(FileId(0), text);
        assert!(errors.is_empty(), "{errors:?}");
        tokens.into_iter().map(|(_, t, _)| t).collect()
    }

    #[test]
    fn signs_are_operators() {
        assert_eq!(
            tokens("x -1"),
            vec![Tok::Ident("x"), Tok::Minus, Tok::Int("1")]
        );
    }

    #[test]
    fn numbers_primes_unknowns_and_unicode() {
        assert_eq!(
            tokens("1.5e-3 2E4 7 x' ?fs rotoïde ++ ||"),
            vec![
                Tok::Float("1.5e-3"),
                Tok::Float("2E4"),
                Tok::Int("7"),
                Tok::Ident("x"),
                Tok::Prime,
                Tok::Unknown("fs"),
                Tok::Ident("rotoïde"),
                Tok::PlusPlus,
                Tok::Parallel
            ]
        );
    }

    #[test]
    fn nested_comments_are_skipped() {
        assert_eq!(
            tokens("a (* b (* c *) d *) e"),
            vec![Tok::Ident("a"), Tok::Ident("e")]
        );
    }

    #[test]
    fn unterminated_comment_points_at_its_opening() {
        let (_, errors) = lex(FileId(0), "let a = 1; (* open (* inner *) ");
        assert_eq!(errors.len(), 1);
        assert_eq!(errors[0].code, "E0102");
        assert_eq!(errors[0].primary_span().map(|s| s.range()), Some(11..13));
    }
}

mod parser {
    use lsdc::diag::Diagnostic;
    use lsdc::source::FileId;
    use lsdc::syntax::ast::{BinaryOp, ExprKind};
    use lsdc::syntax::parser::*;

    use lsdc::syntax::ast::{DeclKind, Expr};

    /// Parses one expression as the value of a `let`: the grammar has one entry point, the
    /// program (a second one would double the generated parser).
    fn parse_expr(text: &str) -> Result<Expr, Vec<Diagnostic>> {
        let (mut program, errors) = parse(FileId(0), &format!("let value = {text};"));
        if !errors.is_empty() {
            return Err(errors);
        }
        let Some(DeclKind::Let(bindings)) = program.decls.pop().map(|decl| decl.kind) else {
            panic!("`let value = {text};` is not one `let`");
        };
        Ok(bindings.into_vec().remove(0).value)
    }

    fn expr(text: &str) -> Expr {
        parse_expr(text).unwrap_or_else(|d| panic!("{d:?}"))
    }

    /// The operator and operands of a binary expression.
    fn binary(e: &Expr) -> Option<(BinaryOp, &Expr, &Expr)> {
        match &e.kind {
            ExprKind::Binary(b) => Some((b.op, &b.lhs, &b.rhs)),
            _ => None,
        }
    }

    #[test]
    fn displacement_binds_tighter_than_frame() {
        let e = expr("[0,0,?s] ++ 1 @ satellite");
        let Some((BinaryOp::Frame, lhs, _)) = binary(&e) else {
            panic!("{e:?}")
        };
        assert!(matches!(binary(lhs), Some((BinaryOp::Displacement, ..))));
    }

    #[test]
    fn unknown_call_binds_tighter_than_product() {
        let e = expr("?fs(x,x')*axe");
        let Some((BinaryOp::Mul, lhs, _)) = binary(&e) else {
            panic!("{e:?}")
        };
        assert!(matches!(lhs.kind, ExprKind::Call(_)));
    }

    #[test]
    fn unary_minus_binds_tightest() {
        let e = expr("-x^2");
        let Some((BinaryOp::Pow, lhs, _)) = binary(&e) else {
            panic!("{e:?}")
        };
        assert!(matches!(lhs.kind, ExprKind::Neg(_)));
        let e = expr("x - 1");
        assert!(matches!(binary(&e), Some((BinaryOp::Sub, ..))));
    }

    #[test]
    fn non_associative_operators_reject_chains() {
        for text in ["a || b || c", "a @ b @ c", "a ++ b ++ c"] {
            assert!(parse_expr(text).is_err(), "{text}");
        }
    }

    #[test]
    fn recovery_reports_several_errors() {
        let (program, errors) = parse(
            FileId(0),
            "let a = ;\nlet b = 1;\njoin x and y with ;\nlet c = 2;",
        );
        assert_eq!(errors.len(), 2, "{errors:?}");
        assert_eq!(program.decls.len(), 4);
    }

    #[test]
    fn names_are_stored_once_per_spelling() {
        let e = expr("b.mass * b.mass");
        let Some((_, lhs, rhs)) = binary(&e) else {
            panic!("{e:?}")
        };
        let (ExprKind::Field(left), ExprKind::Field(right)) = (&lhs.kind, &rhs.kind) else {
            panic!("two field accesses")
        };
        assert!(std::ptr::eq(
            left.field.name.as_str(),
            right.field.name.as_str()
        ));
        let (ExprKind::Name(a), ExprKind::Name(b)) = (&left.target.kind, &right.target.kind) else {
            panic!("two names")
        };
        assert!(std::ptr::eq(a.as_str(), b.as_str()));
    }

    /// A literal of three elements and one of another length read alike, as slices, and print
    /// alike, as lists.
    #[test]
    fn vector_literals_of_any_length_read_as_slices() {
        for (text, len) in [
            ("[1, 2, 3]", 3),
            ("[1, 2]", 2),
            ("[]", 0),
            ("[1, 2, 3, 4]", 4),
        ] {
            let e = expr(text);
            let ExprKind::Vector(elements) = &e.kind else {
                panic!("{e:?}")
            };
            assert_eq!(elements.len(), len, "{text}");
            assert!(format!("{elements:?}").starts_with('['), "{text}");
            let ints: Vec<i64> = elements
                .iter()
                .map(|e| match e.kind {
                    ExprKind::Int(n) => n,
                    _ => panic!("{e:?}"),
                })
                .collect();
            assert_eq!(ints, (1..=len as i64).collect::<Vec<_>>(), "{text}");
        }
    }

    /// A large program holds some forty expressions per body (BENCHMARKS.md, "Memory of
    /// `lsdc check`"): their size is the syntax tree's.
    #[test]
    fn an_expression_takes_24_bytes_and_a_declaration_32() {
        assert_eq!(std::mem::size_of::<Expr>(), 24);
        assert_eq!(std::mem::size_of::<lsdc::syntax::ast::Ident>(), 12);
        assert_eq!(std::mem::size_of::<lsdc::syntax::ast::Decl>(), 32);
    }
}

mod debug_tree {
    use lsdc::source::FileId;
    use lsdc::syntax::debug_tree::pretty;
    use lsdc::syntax::parser::parse;

    /// `pretty` of the compact debug text is Rust's own pretty debug text, for every example,
    /// for strings holding brackets, commas and escaped quotes, and for a sum 150 terms deep.
    #[test]
    fn the_layout_is_that_of_rust_pretty_debug() {
        let mut programs: Vec<String> = (crate::common::example_paths().iter())
            .map(|path| std::fs::read_to_string(path).expect("readable"))
            .collect();
        programs.push(r#"import "a, b {c} [d] (e) \" f.lsd" ; let x = [] ;"#.to_string());
        programs.push(format!("let s = {}1 ;", "1 + ".repeat(149)));
        for text in &programs {
            let (program, _) = parse(FileId(0), text);
            assert_eq!(
                pretty(&format!("{program:?}")),
                format!("{program:#?}"),
                "{text}"
            );
        }
    }
}

mod symbol {
    use lsdc::syntax::symbol::Symbol;

    #[test]
    fn a_spelling_is_one_symbol_and_reads_back() {
        let a = Symbol::intern("symbol_test_alpha");
        let b = Symbol::intern(&String::from("symbol_test_alpha"));
        assert_eq!(a, b);
        assert_eq!(a.as_str(), "symbol_test_alpha");
        assert_ne!(a, Symbol::intern("symbol_test_beta"));
        assert_eq!(std::mem::size_of::<Option<Symbol>>(), 4);
    }

    #[test]
    fn symbols_order_as_their_spellings() {
        // Interned in the reverse of alphabetical order.
        let z = Symbol::intern("symbol_test_zz");
        let a = Symbol::intern("symbol_test_aa");
        assert!(a < z);
        assert_eq!(format!("{a} {z:?}"), "symbol_test_aa \"symbol_test_zz\"");
    }

    #[test]
    fn another_thread_reads_the_same_spelling() {
        let here = Symbol::intern("symbol_test_shared");
        let there = std::thread::spawn(move || (here.as_str(), Symbol::intern("symbol_test_new")))
            .join()
            .unwrap();
        assert_eq!(there.0, "symbol_test_shared");
        assert_eq!(there.1.as_str(), "symbol_test_new");
    }
}

mod arena {
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::Arc;

    use lsdc::source::FileId;
    use lsdc::syntax::arena::{mapped_bytes, Node, Nodes};
    use lsdc::syntax::parser::parse;

    /// Counts its drops.
    #[derive(Clone, Debug)]
    struct Counted(u64, Arc<AtomicUsize>);

    impl PartialEq for Counted {
        fn eq(&self, other: &Counted) -> bool {
            self.0 == other.0
        }
    }

    impl Drop for Counted {
        fn drop(&mut self) {
            self.1.fetch_add(1, Ordering::Relaxed);
        }
    }

    #[test]
    fn nodes_drop_their_values_once_and_give_them_back_whole() {
        let drops = Arc::new(AtomicUsize::new(0));
        let counted = |n| Counted(n, drops.clone());
        let node = Node::new(counted(7));
        let copy = node.clone();
        assert_eq!(node, copy);
        drop(copy);
        assert_eq!(drops.load(Ordering::Relaxed), 1);
        let value = node.into_inner();
        assert_eq!(drops.load(Ordering::Relaxed), 1, "taken out, not dropped");
        assert_eq!(value.0, 7);
        drop(value);

        let list: Nodes<Counted> = (0..5).map(counted).collect();
        assert_eq!(
            list.iter().map(|c| c.0).collect::<Vec<_>>(),
            [0, 1, 2, 3, 4]
        );
        assert_eq!(drops.load(Ordering::Relaxed), 2);
        let vec = list.clone().into_vec();
        assert_eq!(vec.len(), 5);
        assert_eq!(drops.load(Ordering::Relaxed), 2, "moved into the vector");
        drop(vec);
        drop(list);
        assert_eq!(drops.load(Ordering::Relaxed), 12);
        assert!(Nodes::<Counted>::default().is_empty());
        assert!(Nodes::<Counted>::default().into_vec().is_empty());

        // A value larger than a chunk's share has a mapping of its own.
        let large: Nodes<u64> = (0..100_000).collect();
        assert_eq!(large.iter().sum::<u64>(), 4_999_950_000);
    }

    /// The point of the arena: once a tree is dropped, wherever, its chunks go back to the
    /// system. The count of mapped bytes is the whole process's, and other tests parse and drop
    /// trees beside this one, so the measure runs in a process of its own, where every byte is
    /// this tree's.
    #[test]
    fn the_chunks_of_a_dropped_tree_are_unmapped() {
        let name = "unit_syntax::arena::the_chunks_of_a_dropped_tree_are_unmapped";
        if !crate::common::alone(name, &[]) {
            return;
        }
        let text = "let b = body mass = 1.5, iframe = [0.25,0,0] ++ 1 end;\n".repeat(40_000);
        let before = mapped_bytes();
        let (program, parsed) = std::thread::spawn(move || {
            let (program, diagnostics) = parse(FileId(0), &text);
            assert!(diagnostics.is_empty());
            (program, mapped_bytes())
        })
        .join()
        .expect("parsed");
        assert_eq!(program.decls.len(), 40_000);
        let grown = parsed - before;
        println!("the tree took {grown} bytes of chunks");
        assert!(grown > 10 << 20, "the tree took {grown} bytes of chunks");
        // Dropped on another thread than the one that made it, which has ended: every chunk
        // goes back, the one that thread was carving from too.
        drop(program);
        assert_eq!(mapped_bytes(), before, "{parsed} bytes mapped once parsed");
    }
}
