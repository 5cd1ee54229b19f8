//! The constrained accelerations of a mechanism with loops as expressions, for native code
//! (`simulate --compiled`): the KKT system on the rows the run keeps,
//!
//! ```text
//!     [ M    −Gₛᵀ ] [ q' ]   [ S + F ]
//!     [ −Gₛ    0  ] [ λ  ] = [ γₛ    ]      (γₛ = Δ̇ₛ q, the kept rows' bias),
//! ```
//!
//! (the kept rows' equation Gₛ q' = −γₛ negated, so that the matrix is symmetric and each
//! pivot on its diagonal computes half the updates: an LDLᵀ order),
//! eliminated once, when the code is written, in an order fixed then: the elimination's
//! structure (which entries are zero, which pivots, which fill) is known before any state is,
//! so the code does only the arithmetic of the non-zero entries (Duff, Erisman and Reid,
//! *Direct Methods for Sparse Matrices*, 2nd ed., 2017, ch. 10: the analyse phase before the
//! factorise phase). The pivots are taken so that none of them is a geometric entry that
//! vanishes along a regular motion:
//!
//! 1. the tree's coordinates on M's diagonal (M is positive definite on them, and so is every
//!    Schur complement of it: no pivot vanishes), the one with fewest non-zero entries first
//!    (minimum degree, George and Liu, 1981, ch. 5);
//! 2. each complementary coordinate (no inertia: its row of M is zero) with a kept row it
//!    appears in, the one of largest entry at the start: a pair of pivots on that entry (for a
//!    planar loop of revolutes the closing joint's axis, a constant);
//! 3. the remaining multipliers on the diagonal of −Gₛ M⁻¹ Gₛᵀ as reduced by step 2 (negative
//!    definite where the kept rows are independent), again by minimum degree.
//!
//! Where step 1 finds M singular on the tree's coordinates with inertia (the full Delta, with
//! the rods' spins held, at a rate of rod 1p), every kept row is paired with a tree coordinate instead, as step 2 pairs the
//! complementary ones, and only the independent coordinates are left on the diagonal, of the
//! reduced mass matrix (`Order::Paired`): the null-space method. Where the loops share a branch
//! it also writes fewer operations (the full Delta: 8,477 against 13,917 augmented), since the
//! multipliers' block is never formed.
//!
//! A tree coordinate whose row of M is zero (a body without inertia about its joint's axis:
//! the reduced Delta's point nacelle at its universal joint) pivots as the complementary ones
//! do, in step 2. Where M is otherwise not positive definite on the tree (a body without
//! inertia about an oblique axis: a pivot of step 1 is round-off), the system is eliminated
//! again with the augmented Lagrangian's M + ρ GₛᵀGₛ and S + F − ρ Gₛᵀγₛ, which has the same
//! solution and is positive definite wherever the constrained system is regular, every
//! coordinate on its diagonal and the multipliers after them (`Weighting`). The plain order
//! comes first because its M has no fill from GₛᵀGₛ: on the reduced Delta its code is 1,220
//! lines against 1,677 augmented, and 7.9 times faster per right-hand side than the interpreted
//! solve where the augmented one is 2.3 times (BENCHMARKS.md).
//!
//! This is the range-space method (docs/loops.md) written out over the non-zero entries. The
//! coordinates the run leaves at rest (a complementary link's own coordinates that no kept row
//! touches, and the ones whose motions carry no mass, held by the run's choice: the rods'
//! spins of the full Delta) are taken out with their equations. Each pivot is checked in the code against its
//! value at the start: where one falls below 1e-3 of it (near a singular configuration) the
//! accelerations are not-a-number, and the caller evaluates that state otherwise.

use super::expr::{ExprId, Pool, Tape};
use super::lower::Variables;
use super::Equations;

/// What the elimination needs besides the equations.
pub struct KeptRows<'a> {
    /// The constraint rows kept (indices among the six per loop), in the run's order.
    pub rows: &'a [usize],
    /// The coordinates left at rest (their accelerations are 0): a complementary link's own
    /// that no kept row touches and no inertia (a ball's angles).
    pub at_rest: &'a [usize],
    /// The coordinates the run holds at rest by its choice of the motions that carry mass
    /// (`dynamics::loops::solve`, `Massive`: the rods' spins, body-axis rates about the rods):
    /// taken out with their equations as the others at rest, though kept rows or inertia may
    /// touch them. That is the solve with a row a = 0 per coordinate and its multiplier,
    /// which only coordinate's own equation holds: the force that holds a motion without mass.
    pub held: &'a [usize],
    /// How many coordinates come before the complementary links' own.
    pub tree: usize,
    /// A value for every symbol of the pool (a closed state at which to choose the pivots).
    pub symbols: &'a [f64],
}

/// At or below this fraction of its coordinate's diagonal entry at the start, a pivot of step
/// 1 is taken for a zero that round-off left (the diagonal is positive definite there only if
/// each pivot is well above it).
const ROUND_OFF: f64 = 1e-10;

/// A kept row is paired with a tree coordinate whose entry is at least this fraction of the
/// row's largest at the start (`Order::Paired`).
const PAIR_THRESHOLD: f64 = 0.5;

/// Below this fraction of its value at the start, a pivot makes the evaluation fail.
const PIVOT_FLOOR: f64 = 1e-3;

#[derive(Clone, Copy)]
struct Entry {
    expr: ExprId,
    value: f64,
}

/// Sets `equations.accelerations` to the solution of the KKT system on `kept`'s rows, or says
/// why it cannot be written. Where the plain order has no pivot (M singular on the tree's
/// coordinates with inertia), the system is eliminated again with each kept row paired with a
/// tree coordinate (`Order::Paired`), and where that has none either, with M augmented
/// (`Weighting::Augmented`).
pub fn solve_on_kept_rows(equations: &mut Equations, kept: &KeptRows) -> Result<(), String> {
    let pool = equations.pool.clone();
    let attempts = [
        (Weighting::Plain, Order::TreeFirst),
        (Weighting::Plain, Order::Paired),
        (Weighting::Augmented, Order::TreeFirst),
    ];
    let mut refused = String::new();
    for (weighting, order) in attempts {
        match solve(equations, kept, weighting, order) {
            // A refused attempt's expressions are left out with the pool they were put in.
            Err(Refusal::Plain(why)) => {
                equations.pool = pool.clone();
                refused = why;
            }
            result => return result.map_err(Refusal::into_message),
        }
    }
    Err(refused)
}

/// In which order the plain elimination takes its pivots.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Order {
    /// Steps 1, 2 and 3 above: the tree's coordinates on M's diagonal first, then the
    /// complementary ones paired with kept rows, then the multipliers left: the range-space
    /// method. Where the loops share a branch of the tree, eliminating its coordinates fills
    /// the multipliers' block, factored dense in step 3.
    TreeFirst,
    /// Where `TreeFirst` has no pivot: the complementary coordinates paired with kept rows
    /// (step 2), then each kept row left paired with a tree coordinate, a large entry at the
    /// start (`pair_with_largest_entries`; these pivots are those of an LU factorisation of
    /// the dependent coordinates' columns of Gₛ), and then the tree's coordinates left (the
    /// independent ones) on the diagonal of what remains of M, which is the reduced mass
    /// matrix Tᵀ M T with T the basis of the null space of Gₛ these pairs give: the
    /// null-space method (Wehage and Haug, *J. Mech. Des.* 104, 1982, generalised coordinate
    /// partitioning; Nocedal and Wright, *Numerical Optimization*, 2nd ed., 2006, §16.2).
    /// The multipliers' block is never formed: each pair's block pivot [mᵢᵢ g; g 0] adds
    /// nothing to it. It is not the first choice because a tree coordinate's pivot is a
    /// geometric entry, which large motions can take to zero (a four-bar's coupler angle
    /// against a translation row); the pivots' check then hands those states back.
    Paired,
}

/// Which matrix the coordinates' equations carry.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Weighting {
    /// M itself: the tree's coordinates pivot on its diagonal, the complementary ones on a kept
    /// row each (steps 1 and 2 above).
    Plain,
    /// The augmented Lagrangian's M + ρ GₛᵀGₛ, with S + F − ρ Gₛᵀγₛ on the right (Bayo and
    /// García de Jalón, *Kinematic and Dynamic Simulation of Multibody Systems*, 1994, §5.3):
    /// adding ρ Gₛᵀ times the kept rows' equation Gₛ q'' = −γₛ to the coordinates' equations
    /// leaves the solution as it is (q'' and λ both), and makes the matrix positive definite
    /// wherever the constrained system is regular (M ≥ 0 and positive on the null space of
    /// Gₛ, Gₛ of full rank): then every coordinate pivots on the diagonal, tree or
    /// complementary, and no pivot vanishes short of a singular configuration.
    Augmented,
}

/// Why the elimination cannot be written.
enum Refusal {
    /// The plain order has no pivot (M not positive definite on the tree's coordinates with
    /// inertia, or no kept row for a coordinate without): the augmented system may serve.
    Plain(String),
    Other(String),
}

impl Refusal {
    fn into_message(self) -> String {
        match self {
            Refusal::Plain(why) | Refusal::Other(why) => why,
        }
    }
}

/// ρ of the augmented Lagrangian: the trace of M over that of GₛᵀGₛ at the start, so that the
/// added term is of the size of M and the round-off of neither drowns the other (any ρ > 0
/// gives the same solution in exact arithmetic).
fn penalty(mass_diagonal: impl Iterator<Item = f64>, rows: impl Iterator<Item = f64>) -> f64 {
    let mass: f64 = mass_diagonal.map(f64::abs).sum();
    let rows: f64 = rows.map(|g| g * g).sum();
    match mass > 0.0 && rows > 0.0 {
        true => mass / rows,
        false => 1.0,
    }
}

fn solve(
    equations: &mut Equations,
    kept: &KeptRows,
    weighting: Weighting,
    order: Order,
) -> Result<(), Refusal> {
    let n = equations.dimension();
    let values = Tape::new(&equations.pool, &equations.roots()).eval(kept.symbols);
    let entry = |expr: ExprId, value: f64| Entry { expr, value };
    let mut offset = 0;
    let mut take = |count: usize| {
        let range = offset..offset + count;
        offset += count;
        range
    };
    let (mass, second, forces) = (take(n * n), take(n), take(n));
    let rows_total = equations.constraint_rows();
    let (delta, bias) = (take(rows_total * n), take(rows_total));
    let pool = &mut equations.pool;
    // Unknowns: the coordinates not at rest, then the kept rows' multipliers; equations in the
    // same order (a coordinate's, then a kept row's).
    let at_rest = |c: &usize| kept.at_rest.contains(c) || kept.held.contains(c);
    let moving: Vec<usize> = (0..n).filter(|c| !at_rest(c)).collect();
    let (k, m) = (moving.len(), kept.rows.len());
    let size = k + m;
    let mut system = Elimination {
        a: vec![vec![None; size]; size],
        b: Vec::with_capacity(size),
        symmetric: true,
        row_done: vec![false; size],
        column_done: vec![false; size],
        pivots: Vec::new(),
    };
    let set = |pool: &Pool, system: &mut Elimination, i: usize, j: usize, e: Entry| {
        if !pool.is_zero(e.expr) {
            system.a[i][j] = Some(e);
        }
    };
    for (i, &ci) in moving.iter().enumerate() {
        for (j, &cj) in moving.iter().enumerate() {
            let index = ci.min(cj) * n + ci.max(cj);
            let e = entry(equations.mass[index], values[mass.start + index]);
            set(pool, &mut system, i, j, e);
        }
        let f = pool.add(equations.second_member[ci], equations.forces[ci]);
        let value = values[second.start + ci] + values[forces.start + ci];
        system.b.push(entry(f, value));
        // The kept rows' equations negated (−Gₛ q' = γₛ), so that the matrix is symmetric.
        for (r, &row) in kept.rows.iter().enumerate() {
            let g = equations.constraints[row * n + ci];
            let e = entry(pool.neg(g), -values[delta.start + row * n + ci]);
            set(pool, &mut system, i, k + r, e);
            set(pool, &mut system, k + r, i, e);
        }
    }
    for &row in kept.rows {
        let value = values[bias.start + row];
        system.b.push(entry(equations.constraint_bias[row], value));
    }
    if weighting == Weighting::Augmented {
        augment(
            pool,
            &mut system,
            k,
            (&moving, kept.rows),
            |c, r| {
                let index = r * n + c;
                entry(equations.constraints[index], values[delta.start + index])
            },
            |r| entry(equations.constraint_bias[r], values[bias.start + r]),
        );
    }
    // The coordinates at rest must be touched by no kept row and carry no inertia.
    for &c in kept.at_rest {
        let touched = (kept.rows.iter()).any(|&r| !pool.is_zero(equations.constraints[r * n + c]));
        let massive = (0..n).any(|j| !pool.is_zero(equations.mass[c.min(j) * n + c.max(j)]));
        if touched || massive {
            return Err(Refusal::Other(format!(
                "the coordinate {} left at rest moves mass or a kept row",
                coordinate_name(&equations.variables, c)
            )));
        }
    }
    // The tree's coordinates with inertia pivot on M's diagonal (augmented: every
    // coordinate). A tree coordinate whose row of M is zero (a body without inertia about its
    // joint's axis) pivots as the complementary ones do, in step 2.
    let inert = |system: &Elimination, i: usize| (0..k).all(|j| system.a[i][j].is_none());
    let on_diagonal: Vec<usize> = match weighting {
        Weighting::Plain => (0..k)
            .filter(|&i| moving[i] < kept.tree && !inert(&system, i))
            .collect(),
        Weighting::Augmented => (0..k).collect(),
    };
    // A pivot that is round-off of its diagonal entry at the start (M singular on the tree
    // though no row of it is zero: a body without inertia about an oblique axis) is no pivot.
    let diagonal: Vec<f64> = (0..k)
        .map(|i| system.a[i][i].map_or(0.0, |e| e.value.abs()))
        .collect();
    let variables = &equations.variables;
    let name = |i: usize| coordinate_name(variables, moving[i]);
    // The coordinates without inertia, paired with kept rows in either order (step 2).
    let unpaired: Vec<usize> = (0..k).filter(|i| !on_diagonal.contains(i)).collect();
    if order == Order::Paired {
        pair_with_kept_rows(&mut system, pool, k, &unpaired, name)?;
        pair_with_largest_entries(&mut system, pool, k, &on_diagonal);
    }
    // 1. The tree's coordinates with inertia left, on M's diagonal (augmented: every
    // coordinate), by minimum degree.
    while let Some(i) = system.fewest_entries(on_diagonal.iter().map(|&i| (i, i))) {
        let floor = ROUND_OFF * diagonal[i];
        if system.a[i][i].is_none_or(|p| p.value <= floor) {
            let at = name(i);
            return Err(match weighting {
                Weighting::Plain => Refusal::Plain(format!(
                    "the mass matrix is not positive definite on the tree (at {at})"
                )),
                Weighting::Augmented => Refusal::Other(format!(
                    "the mass matrix is not positive definite where the kept rows allow motion \
                     (at {at})"
                )),
            });
        }
        system.eliminate(pool, i, i);
    }
    // 2. Each complementary coordinate with its largest kept row (plain only).
    pair_with_kept_rows(&mut system, pool, k, &unpaired, name)?;
    // 3. The remaining multipliers, on −Gₛ M⁻¹ Gₛᵀ (negative definite where the kept rows are
    // independent).
    let rest: Vec<usize> = (k..size).filter(|&r| !system.row_done[r]).collect();
    while let Some(r) = system.fewest_entries(rest.iter().map(|&r| (r, r))) {
        if system.a[r][r].is_none_or(|p| p.value >= 0.0) {
            return Err(match weighting {
                Weighting::Plain => Refusal::Plain(
                    "the kept rows are not independent at the start, by the plain order".into(),
                ),
                Weighting::Augmented => {
                    Refusal::Other("the kept rows are not independent at the start".into())
                }
            });
        }
        system.eliminate(pool, r, r);
    }
    let solution = system.substitute(pool);
    let zero = pool.constant(0.0);
    let mut accelerations = vec![zero; n];
    for (i, &c) in moving.iter().enumerate() {
        accelerations[c] = solution[i];
    }
    // The pivots' check, on the first acceleration: not-a-number below the floor.
    let not_a_number = pool.constant(f64::NAN);
    let mut checked = accelerations[moving.first().copied().unwrap_or(0)];
    for &(_, _, pivot) in system.pivots.iter().rev() {
        let sign = pool.constant(pivot.value.signum());
        let floor = pool.constant(PIVOT_FLOOR * pivot.value.abs());
        let signed = pool.mul(pivot.expr, sign);
        let test = pool.sub(signed, floor);
        checked = pool.select(test, checked, not_a_number);
    }
    if let Some(&first) = moving.first() {
        accelerations[first] = checked;
    }
    equations.accelerations = Some(accelerations);
    Ok(())
}

/// Pairs each of `columns` not yet eliminated (coordinates without inertia) with the kept row
/// of largest entry in its column among those left (steps 2): a symmetric block pivot on that
/// entry, which leaves the rest symmetric. The kept rows are the rows after the first `k`.
fn pair_with_kept_rows(
    system: &mut Elimination,
    pool: &mut Pool,
    k: usize,
    columns: &[usize],
    name: impl Fn(usize) -> String,
) -> Result<(), Refusal> {
    for &i in columns {
        if system.column_done[i] {
            continue;
        }
        let largest = (k..system.a.len())
            .filter(|&r| !system.row_done[r])
            .filter_map(|r| system.a[r][i].map(|e| (r, e.value.abs())))
            .max_by(|x, y| x.1.total_cmp(&y.1));
        let Some((r, _)) = largest.filter(|&(_, v)| v > 0.0) else {
            return Err(Refusal::Plain(format!(
                "no kept row determines the coordinate {}",
                name(i)
            )));
        };
        system.pair(pool, i, r);
    }
    Ok(())
}

/// Pairs each kept row left with one of `columns` (tree coordinates with inertia)
/// (`Order::Paired`), until no kept row is left or none of them has an entry in the columns
/// left: each time, of the entries within `PAIR_THRESHOLD` of their row's largest at the
/// start, the one whose pair has the fewest entries in its two rows (threshold pivoting with
/// Markowitz's count: Duff, Erisman and Reid, 2017, §5.4 and §9.2), the larger entry on a tie.
fn pair_with_largest_entries(
    system: &mut Elimination,
    pool: &mut Pool,
    k: usize,
    columns: &[usize],
) {
    loop {
        let open = &*system;
        let degree = |row: usize| {
            let open_columns = (0..open.a.len()).filter(|&j| !open.column_done[j]);
            open_columns.filter(|&j| open.a[row][j].is_some()).count()
        };
        let mut best: Option<(usize, usize, usize, f64)> = None;
        for r in (k..open.a.len()).filter(|&r| !open.row_done[r]) {
            let entries: Vec<(usize, f64)> = (columns.iter())
                .filter(|&&i| !open.column_done[i])
                .filter_map(|&i| open.a[r][i].map(|e| (i, e.value.abs())))
                .collect();
            let largest = entries.iter().map(|e| e.1).fold(0.0, f64::max);
            let large = |&(_, v): &(usize, f64)| v > 0.0 && v >= PAIR_THRESHOLD * largest;
            for (i, v) in entries.into_iter().filter(large) {
                let count = degree(r) + degree(i);
                let better = best.is_none_or(|(.., c, w)| count < c || (count == c && v > w));
                if better {
                    best = Some((r, i, count, v));
                }
            }
        }
        match best {
            Some((r, i, ..)) => system.pair(pool, i, r),
            None => return,
        }
    }
}

/// The name of the coordinate of rate `c`: its position's for a declared coordinate, the
/// rate's itself for a ball's body rate.
fn coordinate_name(variables: &Variables, c: usize) -> String {
    let rate = &variables.rates[c].name;
    rate.strip_suffix('\'').unwrap_or(rate).to_string()
}

/// Adds ρ Gₛᵀ Gₛ to the coordinates' block of `system` (its first `k` rows and columns) and
/// −ρ Gₛᵀ γₛ to their right-hand side (`Weighting::Augmented`): `moving` are the coordinates,
/// `rows` the kept rows, `g(c, r)` the entry of row r at coordinate c, `gamma(r)` row r's bias.
fn augment(
    pool: &mut Pool,
    system: &mut Elimination,
    k: usize,
    (moving, rows): (&[usize], &[usize]),
    g: impl Fn(usize, usize) -> Entry,
    gamma: impl Fn(usize) -> Entry,
) {
    let columns: Vec<Vec<Option<Entry>>> = (moving.iter())
        .map(|&c| {
            let column = rows
                .iter()
                .map(|&r| Some(g(c, r)).filter(|e| !pool.is_zero(e.expr)));
            column.collect()
        })
        .collect();
    let mass_diagonal = (0..k).filter_map(|i| system.a[i][i].map(|e| e.value));
    let all_rows = columns.iter().flatten().flatten().map(|e| e.value);
    let rho = penalty(mass_diagonal, all_rows);
    let rho = Entry {
        expr: pool.constant(rho),
        value: rho,
    };
    // (Gᵀ G)ᵢⱼ over the rows both coordinates appear in, then times ρ.
    let weighted_dot = |pool: &mut Pool, x: &[Option<Entry>], y: &[Option<Entry>]| {
        let mut terms = Vec::new();
        let mut value = 0.0;
        for (a, b) in x.iter().zip(y) {
            if let (Some(a), Some(b)) = (a, b) {
                let term = product(pool, *a, *b);
                terms.push(term.expr);
                value += term.value;
            }
        }
        (!terms.is_empty()).then(|| {
            let sum = Entry {
                expr: pool.sum(terms),
                value,
            };
            product(pool, rho, sum)
        })
    };
    let add_to = |pool: &mut Pool, entry: &mut Option<Entry>, added: Entry| {
        *entry = Some(match *entry {
            None => added,
            Some(old) => Entry {
                expr: pool.add(old.expr, added.expr),
                value: old.value + added.value,
            },
        });
    };
    let biases: Vec<Option<Entry>> = rows.iter().map(|&r| Some(gamma(r))).collect();
    for i in 0..k {
        // ρ GᵀG is symmetric: each pair's dot product is formed once and added to both entries.
        for j in i..k {
            let Some(added) = weighted_dot(pool, &columns[i], &columns[j]) else {
                continue;
            };
            add_to(pool, &mut system.a[i][j], added);
            if j != i {
                add_to(pool, &mut system.a[j][i], added);
            }
        }
        if let Some(added) = weighted_dot(pool, &columns[i], &biases) {
            let old = system.b[i];
            system.b[i] = Entry {
                expr: pool.sub(old.expr, added.expr),
                value: old.value - added.value,
            };
        }
    }
}

/// A linear system eliminated in an order chosen as it goes, on expressions and on their values
/// at the start alike.
struct Elimination {
    a: Vec<Vec<Option<Entry>>>,
    b: Vec<Entry>,
    /// Whether `a` is symmetric (in its values: the augmented entries are formed twice, the
    /// same sums): then a pivot on the diagonal updates the upper triangle and mirrors it, as
    /// an LDLᵀ factorisation does (Golub and Van Loan, *Matrix Computations*, 4th ed., 2013,
    /// §4.1), half the products. False between the two pivots of a pair (step 2).
    symmetric: bool,
    row_done: Vec<bool>,
    column_done: Vec<bool>,
    /// (row, column, pivot), in the order taken.
    pivots: Vec<(usize, usize, Entry)>,
}

impl Elimination {
    /// Of the candidate (row, column) pivots not yet taken, the one whose column has the fewest
    /// non-zero entries left.
    fn fewest_entries(&self, candidates: impl Iterator<Item = (usize, usize)>) -> Option<usize> {
        candidates
            .filter(|&(r, c)| !self.row_done[r] && !self.column_done[c])
            .min_by_key(|&(_, c)| {
                (0..self.a.len())
                    .filter(|&r| !self.row_done[r] && self.a[r][c].is_some())
                    .count()
            })
            .map(|(r, _)| r)
    }

    /// Eliminates column `column` from every row not yet taken, by row `row`.
    fn eliminate(&mut self, pool: &mut Pool, row: usize, column: usize) {
        let pivot = self.a[row][column].expect("a pivot is a non-zero entry");
        let one = pool.constant(1.0);
        let reciprocal = Entry {
            expr: pool.div(one, pivot.expr),
            value: 1.0 / pivot.value,
        };
        self.row_done[row] = true;
        self.column_done[column] = true;
        self.pivots.push((row, column, pivot));
        let pivot_row: Vec<(usize, Entry)> = (0..self.a.len())
            .filter(|&j| !self.column_done[j])
            .filter_map(|j| self.a[row][j].map(|e| (j, e)))
            .collect();
        let pivot_b = self.b[row];
        // On a symmetric matrix's diagonal, entry (i, j) with j < i was written as the mirror
        // of (j, i), whose row came first.
        let mirrored = self.symmetric && row == column;
        for i in 0..self.a.len() {
            if self.row_done[i] {
                continue;
            }
            let Some(below) = self.a[i][column].take() else {
                continue;
            };
            let factor = product(pool, below, reciprocal);
            for &(j, e) in pivot_row.iter().filter(|&&(j, _)| !mirrored || j >= i) {
                let update = product(pool, factor, e);
                self.a[i][j] = match self.a[i][j] {
                    None => Some(negated(pool, update)),
                    Some(old) => {
                        let new = Entry {
                            expr: pool.sub(old.expr, update.expr),
                            value: old.value - update.value,
                        };
                        (!pool.is_zero(new.expr)).then_some(new)
                    }
                };
                if mirrored {
                    self.a[j][i] = self.a[i][j];
                }
            }
            let update = product(pool, factor, pivot_b);
            let old = self.b[i];
            self.b[i] = Entry {
                expr: pool.sub(old.expr, update.expr),
                value: old.value - update.value,
            };
        }
    }

    /// Eliminates coordinate `column` by kept row `row` and the row's multiplier by the
    /// coordinate's equation: the symmetric block pivot [mᵢᵢ g; g 0] on their entry g, after
    /// which what is left is symmetric again.
    fn pair(&mut self, pool: &mut Pool, column: usize, row: usize) {
        self.symmetric = false;
        self.eliminate(pool, column, row);
        self.eliminate(pool, row, column);
        self.mirror_upper_triangle();
    }

    /// Makes the rows and columns not yet taken symmetric again by their upper triangle, after
    /// a pivot that left them symmetric in value but not entry for entry.
    fn mirror_upper_triangle(&mut self) {
        let open: Vec<usize> = (0..self.a.len()).filter(|&i| !self.row_done[i]).collect();
        for (n, &i) in open.iter().enumerate() {
            for &j in &open[n + 1..] {
                self.a[j][i] = self.a[i][j];
            }
        }
        self.symmetric = true;
    }

    /// The unknowns by back substitution, in the pivots' reverse order: each pivot's row holds,
    /// besides the pivot, only the columns eliminated after it.
    fn substitute(&self, pool: &mut Pool) -> Vec<ExprId> {
        let zero = pool.constant(0.0);
        let one = pool.constant(1.0);
        let mut x = vec![zero; self.a.len()];
        for &(row, column, pivot) in self.pivots.iter().rev() {
            let mut sum = self.b[row].expr;
            for (j, e) in self.a[row].iter().enumerate() {
                if let Some(e) = e.filter(|_| j != column) {
                    let term = pool.mul(e.expr, x[j]);
                    sum = pool.sub(sum, term);
                }
            }
            let reciprocal = pool.div(one, pivot.expr);
            x[column] = pool.mul(sum, reciprocal);
        }
        x
    }
}

fn product(pool: &mut Pool, a: Entry, b: Entry) -> Entry {
    Entry {
        expr: pool.mul(a.expr, b.expr),
        value: a.value * b.value,
    }
}

fn negated(pool: &mut Pool, a: Entry) -> Entry {
    Entry {
        expr: pool.neg(a.expr),
        value: -a.value,
    }
}
