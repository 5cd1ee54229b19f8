//! Unit tests of `src/diag/`: the did-you-mean suggestions.
//! Each module holds the tests of the file of `src/` it is named after, kept out of the library
//! so that `cargo test` compiles the library once (`test = false` in Cargo.toml).

mod suggest {
    use lsdc::diag::suggest::*;

    #[test]
    fn close_names_are_suggested() {
        assert_eq!(
            did_you_mean("satelite", ["earth", "satellite"]),
            Some("satellite")
        );
        assert_eq!(did_you_mean("iframe", ["frame", "mass"]), Some("frame"));
        assert_eq!(did_you_mean("zzz", ["satellite"]), None);
    }

    #[test]
    fn thesis_body_names_are_recognised() {
        assert_eq!(thesis_body_number("S1"), Some(1));
        assert_eq!(thesis_body_number("S_12"), Some(12));
        assert_eq!(thesis_body_number("S0"), None);
        assert_eq!(thesis_body_number("Sx"), None);
    }
}
