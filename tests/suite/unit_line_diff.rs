//! The unified line diff that `lsdc fmt --check` prints.

use lsdc::ide::line_diff::unified;

#[test]
fn same_lines_make_no_diff() {
    assert_eq!(unified("a\nb\n", "a\nb\n", "x", "y"), "");
}

#[test]
fn a_changed_line_in_its_context() {
    let old = "1\n2\n3\n4\n5\n6\n7\n8\n9\n";
    let new = "1\n2\n3\n4\nfive\n6\n7\n8\n9\n";
    let expected = "--- x\n+++ y\n@@ -2,7 +2,7 @@\n 2\n 3\n 4\n-5\n+five\n 6\n 7\n 8\n";
    assert_eq!(unified(old, new, "x", "y"), expected);
}

#[test]
fn distant_changes_make_two_hunks_and_an_insertion_counts_from_the_line_before() {
    let old = "a\nb\nc\nd\ne\nf\ng\nh\ni\nj\n";
    let new = "A\nb\nc\nd\ne\nf\ng\nh\ni\nj\nk\n";
    let expected =
        "--- x\n+++ y\n@@ -1,4 +1,4 @@\n-a\n+A\n b\n c\n d\n@@ -8,3 +8,4 @@\n h\n i\n j\n+k\n";
    assert_eq!(unified(old, new, "x", "y"), expected);
}
