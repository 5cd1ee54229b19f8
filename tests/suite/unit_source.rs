//! Unit tests of `src/source/`: compact spans.

mod span {
    use lsdc::source::{FileId, Span};

    #[test]
    fn a_span_is_eight_bytes() {
        assert_eq!(std::mem::size_of::<Span>(), 8);
        assert_eq!(std::mem::size_of::<Option<Span>>(), 12);
    }

    #[test]
    fn short_and_long_spans_read_back() {
        let cases = [
            (FileId(0), 0, 0),
            (FileId(3), 10, 65_545), // the longest short span
            (FileId(3), 10, 65_546), // one byte longer
            (FileId(65_534), 7, 9),  // the last file of the short form
            (FileId(65_535), 7, 9),  // the first file past it
            (FileId(1), 4_000_000_000, 4_000_000_001),
        ];
        for (file, start, end) in cases {
            let span = Span::new(file, start, end);
            assert_eq!((span.file(), span.range()), (file, start..end));
            assert_eq!(span, Span::new(file, start, end));
        }
    }

    #[test]
    fn spans_order_and_join_by_position_whatever_their_form() {
        let long = Span::new(FileId(2), 5, 100_000);
        let short = Span::new(FileId(2), 6, 8);
        assert!(long < short);
        assert_eq!(short.to(long), long);
        assert_eq!(
            Span::new(FileId(2), 99_990, 100_001).to(short).range(),
            6..100_001
        );
        assert!(Span::new(FileId(1), 9, 10) < long);
    }
}
