//! Unit tests of `src/topology/`: the breadth-first spanning tree.
//! Kept out of the library so that `cargo test` compiles the library once (`test = false` in
//! Cargo.toml).

use lsdc::elab::value::JoinId;
use lsdc::topology::*;

#[test]
fn breadth_first_marks_the_closing_join_of_an_odd_cycle() {
    // earth(0) - 1 - 2 - 3 - earth, joins in order 0-1, 1-2, 2-3, 3-0.
    let incident = vec![
        vec![(JoinId(0), 1), (JoinId(3), 3)],
        vec![(JoinId(0), 0), (JoinId(1), 2)],
        vec![(JoinId(1), 1), (JoinId(2), 3)],
        vec![(JoinId(2), 2), (JoinId(3), 0)],
    ];
    let (order, tree, loops) = breadth_first(&incident);
    assert_eq!(order, vec![1, 3, 2]);
    assert_eq!(loops, vec![JoinId(2)]);
    assert_eq!(tree[&2], (JoinId(1), 1));
}
