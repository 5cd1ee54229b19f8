//! Unit tests of `src/load/`: reading a program's text, and the pieces of the URDF import.
//! Each module holds the tests of the file of `src/` it is named after, kept out of the library
//! so that `cargo test` compiles the library once (`test = false` in Cargo.toml).

mod urdf {
    use lsdc::load::urdf::*;
    use lsdc::source::FileId;
    use lsdc::syntax::lexer::{lex, Tok};

    fn import(xml: &str) -> Imported {
        import_urdf("test.urdf", xml, &ImportOptions::default()).unwrap_or_else(|d| panic!("{d:?}"))
    }

    #[test]
    fn materials_alone_are_reported_once() {
        let imported = import("<robot name=\"r\"><material name=\"m\"/><material name=\"n\"/><link name=\"a\"/></robot>");
        let messages: Vec<&str> = imported
            .warnings
            .iter()
            .map(|d| d.message.as_str())
            .collect();
        assert_eq!(messages, ["the robot's materials are not imported"]);
        assert_eq!(
            imported.warnings[0].notes,
            ["the robot defines 2 materials"]
        );
    }

    #[test]
    fn comments_cannot_be_closed_by_names() {
        let imported = import("<robot name=\"a*)b(*c\"><link name=\"x*)\"/></robot>");
        let (tokens, errors) = lex(FileId(0), &imported.text);
        assert!(errors.is_empty(), "{}", imported.text);
        assert!(matches!(tokens[0].1, Tok::Import), "{}", imported.text);
        assert!(
            imported
                .text
                .contains("let x__ = body mass = 0, inertia = 0 end ; (* URDF link \"x* )\" *)"),
            "{}",
            imported.text
        );
    }
}

mod document {
    use lsdc::load::urdf::document::*;
    use lsdc::source::FileId;
    use std::borrow::Cow;

    #[test]
    fn attributes_and_entities_are_read() {
        let xml = "<?xml version=\"1.0\"?><!-- c --><robot name='a&amp;b&#x41;'><link name = \"l\" /></robot>";
        let source = Source::parse(FileId(0), xml).expect("parses");
        let root = source.root();
        assert_eq!(root.attribute("name"), Some("a&bA"));
        let link = child(root, "link").expect("a link");
        assert_eq!(parent(link), Some(root));
        assert_eq!(link.attribute("name"), Some("l"));
        let span = source.span(link);
        assert_eq!(&xml[span.range()], "<link name = \"l\" />");
        let span = source.attribute_span(link, "name");
        assert_eq!(&xml[span.range()], "name = \"l\"");
    }

    #[test]
    fn start_tags_end_after_attributes_holding_a_greater_than() {
        let xml = "<robot name=\"a>b\"\n  >text</robot>";
        let source = Source::parse(FileId(0), xml).expect("parses");
        let span = source.span(source.root());
        assert_eq!(&xml[span.range()], "<robot name=\"a>b\"\n  >");
    }

    #[test]
    fn malformed_xml_is_located() {
        let xml = "<robot name=\"r\">\n  <link name=\"a\">\n</robot>\n";
        let error = Source::parse(FileId(0), xml).err().expect("malformed");
        assert_eq!(error.code, "E1001");
        let span = error.primary_span().expect("located");
        assert_eq!(&xml[span.range()], "</robot>");
        let xml = "<robot><link/><!-- é\n never closed </robot>";
        let error = Source::parse(FileId(0), xml).err().expect("malformed");
        let span = error.primary_span().expect("located");
        assert_eq!(span.range().start, xml.find("<!--").expect("there"));
        for xml in [
            "",
            "<robot",
            "<robot name=\"r>",
            "<robot><!-- </robot>",
            "<robot></link>",
            "text",
            "<a/><b/>",
            "é<",
            "<robot>\n<é",
        ] {
            let error = Source::parse(FileId(0), xml).err().expect(xml);
            assert_eq!(error.code, "E1001", "{xml}");
            let span = error.primary_span().expect(xml);
            assert!(span.range().end <= xml.len(), "{xml}");
        }
    }

    #[test]
    fn textures_without_file_are_blanked_for_urdf_rs() {
        let xml = "<robot name=\"r\"><material name=\"m\"><texture a=\"é\">\n</texture><texture filename=\"t.png\"/></material><link name=\"a\"/></robot>";
        let source = Source::parse(FileId(0), xml).expect("parses");
        let text = source.urdf_text();
        assert_eq!(text.len(), xml.len());
        assert_eq!(text.matches('\n').count(), 1);
        assert!(
            !text.contains("<texture a=") && !text.contains("</texture>"),
            "{text}"
        );
        assert!(text.contains("<texture filename=\"t.png\"/>"), "{text}");
        assert!(urdf_rs::read_from_string(&text).is_ok());
        let source = Source::parse(FileId(0), "<robot/>").expect("parses");
        assert!(matches!(source.urdf_text(), Cow::Borrowed(_)));
    }
}

mod inertia {
    use lsdc::load::urdf::inertia::*;
    use nalgebra::{Matrix3, Rotation3, Vector3};

    #[test]
    fn a_nearly_diagonal_tensor_gets_a_small_rotation() {
        let tensor = Matrix3::new(3.0, 1e-3, 0.0, 1e-3, 2.0, 0.0, 0.0, 0.0, 1.0);
        let principal = principal(&tensor);
        let axes = principal.axes.expect("not diagonal");
        assert!(axes.angle() < 1e-2, "{}", axes.angle());
        assert!((principal.moments - Vector3::new(3.0, 2.0, 1.0)).amax() < 1e-5);
        let rebuilt =
            axes.matrix() * Matrix3::from_diagonal(&principal.moments) * axes.matrix().transpose();
        assert!((rebuilt - tensor).amax() < 1e-15);
    }

    #[test]
    fn axis_angle_is_exact_for_small_and_half_turns() {
        let turns = [
            (1e-9, Vector3::new(0.0, 0.6, 0.8)),
            (std::f64::consts::PI - 1e-12, Vector3::x()),
            (2.0, Vector3::new(1.0, 2.0, 3.0)),
        ];
        for (angle, axis) in turns {
            let rotation = Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(axis), angle);
            let (found, found_axis) = axis_angle(&rotation).expect("not the identity");
            let back =
                Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(found_axis), found);
            assert!(
                (back.matrix() - rotation.matrix()).amax() < 1e-15,
                "{angle}"
            );
        }
        assert!(axis_angle(&Rotation3::identity()).is_none());
    }
}

mod lsd {
    use lsdc::diag::number::shortest as number;
    use lsdc::load::urdf::lsd::*;
    use lsdc::source::FileId;
    use lsdc::syntax::lexer::{lex, Tok};
    use nalgebra::Vector3;

    #[test]
    fn numbers_read_back_exactly_and_lex_as_numbers() {
        for x in [
            0.1,
            1e-7,
            1e21,
            -0.5,
            2.5e-5,
            1e16,
            123456789.125,
            f64::MAX,
            f64::MIN_POSITIVE,
            5e-324,
            -3.0,
        ] {
            let text = number(x);
            let magnitude = text.trim_start_matches('-');
            let (tokens, errors) = lex(FileId(0), magnitude);
            assert!(errors.is_empty() && tokens.len() == 1, "{text}");
            assert!(matches!(tokens[0].1, Tok::Int(_) | Tok::Float(_)), "{text}");
            assert_eq!(
                magnitude.parse::<f64>().unwrap_or(f64::NAN),
                x.abs(),
                "{text}"
            );
        }
        assert_eq!(number(-0.0), "0");
        assert_eq!(number(1e-7), "1e-7");
        assert_eq!(number(0.25), "0.25");
    }

    #[test]
    fn planar_axes_span_the_plane() {
        assert_eq!(planar(&Vector3::z()), "planar");
        assert_eq!(
            planar(&Vector3::x()),
            "link(x, y, q) dof1 = x * [0, 1, 0] + y * [0, 0, 1], dof2 = q || [1, 0, 0] end"
        );
        assert_eq!(
            planar(&Vector3::y()),
            "link(x, y, q) dof1 = x * [0, 0, 1] + y * [1, 0, 0], dof2 = q || [0, 1, 0] end"
        );
    }
}

mod names {
    use lsdc::load::urdf::lsd_name;

    #[test]
    fn names_follow_the_documented_rule() {
        assert_eq!(lsd_name("base_link"), "base_link");
        assert_eq!(lsd_name("base-link"), "base_link");
        assert_eq!(lsd_name("1st"), "_1st");
        assert_eq!(lsd_name("with"), "with_");
        assert_eq!(lsd_name("earth"), "earth_");
        assert_eq!(lsd_name("revolute"), "revolute_");
        assert_eq!(lsd_name("g"), "g_");
        assert_eq!(lsd_name("joints"), "joints_");
        assert_eq!(lsd_name("continuous"), "continuous_");
        assert_eq!(lsd_name("sin"), "sin_");
        assert_eq!(lsd_name("bras_rotoïde"), "bras_rotoïde");
        assert_eq!(lsd_name(""), "_");
        assert_eq!(lsd_name("a b/c"), "a_b_c");
    }
}

mod reading {
    use lsdc::load::{read_bounded, MAX_SOURCE_BYTES};

    /// An endless input (`lsdc check /dev/zero` grew by 1.9 GB a second) is refused once past
    /// the limit, with the limit in the message; a text at the limit is read whole.
    #[test]
    fn an_endless_input_is_refused_at_the_limit() {
        let endless = std::io::repeat(b'(');
        let error = read_bounded(endless, 1000).expect_err("refused");
        assert_eq!(error.kind(), std::io::ErrorKind::FileTooLarge);
        assert!(
            error.to_string().contains("longer than 1000 bytes"),
            "{error}"
        );
        let text = "x".repeat(1000);
        assert_eq!(read_bounded(text.as_bytes(), 1000).expect("read"), text);
        // Well above the largest generated mechanisms (10^6 bodies: about 210 MiB).
        assert_eq!(MAX_SOURCE_BYTES, 1 << 30);
    }
}
