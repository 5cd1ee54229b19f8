//! Heap allocations per right-hand side and per projection, on every example: a counting global
//! allocator around the system allocator (`common/counting.rs`) counts the calls to `alloc` (and
//! `realloc`) made while one derivative is evaluated at the example's initial state, after two
//! of each have sized every scratch buffer. Run with `cargo bench --bench allocations`.

#[path = "common/counting.rs"]
mod counting;

fn main() {
    println!(
        "{:<36} {:>6} {:>12} {:>12}",
        "example", "loops", "per RHS", "per projection"
    );
    for file in counting::examples() {
        let Some((loops, rhs, projection)) = counting::per_evaluation(&file) else {
            continue;
        };
        let projection = projection.map_or("-".to_string(), |n| n.to_string());
        let name = file.display().to_string();
        println!(
            "{:<36} {loops:>6} {rhs:>12} {projection:>12}",
            name.trim_start_matches("examples/"),
        );
    }
}
