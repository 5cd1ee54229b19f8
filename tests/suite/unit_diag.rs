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

    /// Two adjacent characters swapped are one slip: `earht` and `swnig` are one edit from
    /// `earth` and `swing` (plain Levenshtein counts two, beyond the limit of a five-letter name).
    #[test]
    fn swapped_neighbours_are_one_edit() {
        assert_eq!(did_you_mean("earht", ["earth", "rod"]), Some("earth"));
        assert_eq!(did_you_mean("swnig", ["swing", "rod"]), Some("swing"));
        assert_eq!(did_you_mean("ra", ["ar", "rod"]), Some("ar"));
        // A transposition elsewhere in a longer name, and one besides a substitution.
        assert_eq!(did_you_mean("satellitte", ["satellite"]), Some("satellite"));
        assert_eq!(
            did_you_mean("setallite", ["satellite", "earth"]),
            Some("satellite")
        );
        // Swapping is not a licence for anagrams.
        assert_eq!(did_you_mean("htrae", ["earth"]), None);
    }

    #[test]
    fn thesis_body_names_are_recognised() {
        assert_eq!(thesis_body_number("S1"), Some(1));
        assert_eq!(thesis_body_number("S_12"), Some(12));
        assert_eq!(thesis_body_number("S0"), None);
        assert_eq!(thesis_body_number("Sx"), None);
    }
}
