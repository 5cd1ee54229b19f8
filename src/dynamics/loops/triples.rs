//! The kept rows' normal matrix factored by blocks of three rows, wherever every loop keeps
//! exactly three rows, contiguous in the kept order (`kept_by_threes`): a planar loop's three
//! rows in its plane, in planar form (`planar_rows`) or in spatial form alike. A loop's rows
//! share its columns, so the envelope of A (`factored::Envelope`) then starts every block of
//! three rows at the same block column. The
//! factor is the same Cholesky factor L as the rows' (A = LLᵀ, stored in the same envelope,
//! equal to round-off), taken by 3 × 3 blocks (Golub and Van Loan, Matrix Computations, 4th
//! ed., § 4.2.9, block Cholesky), with the reciprocals of its diagonal kept beside it for the
//! substitutions.
//!
//! Why by blocks: the row-by-row factor and its substitutions are each one chain of dependent
//! square roots and divisions, one link per row (row k + 1 waits on row k's pivot), and that
//! chain, not the arithmetic, sets their time. By blocks, the chain is carried by the pivots
//! d of the block's LDLᵀ factor, each waiting on one division (the square roots and the
//! Cholesky entries are taken beside it, off the chain), and the substitutions multiply by the
//! diagonal's reciprocals where the rows' divide.

/// What a factor by blocks keeps of each diagonal block L_KK = L̃ D^½ (L̃ unit lower
/// triangular, D the pivots).
#[derive(Clone, Copy, Debug, Default)]
pub struct DiagonalBlock {
    /// L_KK's entries below its diagonal, (1, 0), (2, 0), (2, 1), and the reciprocals of its
    /// diagonal.
    lower: [f64; 3],
    inverse_roots: [f64; 3],
    /// L̃⁻¹'s entries below its unit diagonal: (1, 0), (2, 0), (2, 1).
    unit_inverse: [f64; 3],
    /// D⁻¹.
    reciprocals: [f64; 3],
}

/// A 3 × 3 block, by rows.
type Block = [[f64; 3]; 3];

/// Where the envelope holds row `row`'s entry in column `column`.
fn at(first: &[usize], starts: &[usize], row: usize, column: usize) -> usize {
    starts[row] + column - first[row]
}

/// Whether every loop keeps exactly three rows, contiguous in the kept order: `indices` (the
/// kept rows, each among its loop's 6) by threes, each three of one loop, and no loop in two
/// threes. The decision rests on the kept rows alone, never on the form that made them.
pub fn kept_by_threes(indices: &[usize], loops: usize) -> bool {
    if indices.is_empty() || !indices.len().is_multiple_of(3) {
        return false;
    }
    let mut seen = vec![false; loops];
    indices.chunks_exact(3).all(|three| {
        let owner = three[0] / 6;
        let one_loop = three.iter().all(|&r| r / 6 == owner);
        let first_time = owner < loops && !std::mem::replace(&mut seen[owner], true);
        one_loop && first_time
    })
}

/// Whether an envelope with these rows' first columns is laid out by blocks of three rows:
/// every block's three rows start at one column, the first of a block.
pub fn by_triples(first: &[usize]) -> bool {
    first.len().is_multiple_of(3)
        && first
            .chunks_exact(3)
            .all(|f| f[0].is_multiple_of(3) && f[1] == f[0] && f[2] == f[0])
}

/// Block row K's entries in block column J (J < K, within the envelope).
fn block(first: &[usize], starts: &[usize], values: &[f64], k: usize, j: usize) -> Block {
    let mut out = [[0.0; 3]; 3];
    for (i, row) in out.iter_mut().enumerate() {
        let start = at(first, starts, 3 * k + i, 3 * j);
        row.copy_from_slice(&values[start..start + 3]);
    }
    out
}

/// The Cholesky factor of the envelope `values` (laid out by triples, `by_triples`) in place,
/// its diagonal blocks' inverses into `blocks`; or the first row whose pivot is not positive
/// (the rows' factor's failure, `Envelope::cholesky`).
pub fn cholesky(
    first: &[usize],
    starts: &[usize],
    values: &mut [f64],
    blocks: &mut Vec<DiagonalBlock>,
) -> Result<(), usize> {
    blocks.clear();
    for k in 0..first.len() / 3 {
        let m = first[3 * k] / 3;
        // A_KK's lower triangle, less Σ_J L_KJ L_KJᵀ as the blocks J are found.
        let mut diagonal = [[0.0; 3]; 3];
        for (i, row) in diagonal.iter_mut().enumerate() {
            let start = at(first, starts, 3 * k + i, 3 * k);
            row[..=i].copy_from_slice(&values[start..=start + i]);
        }
        for j in m..k {
            // S = A_KJ − Σ_I L_KI L_JIᵀ over the blocks I both rows hold.
            let mut s = block(first, starts, values, k, j);
            for i in m.max(first[3 * j] / 3)..j {
                let (left, right) = (
                    block(first, starts, values, k, i),
                    block(first, starts, values, j, i),
                );
                subtract_product(&mut s, &left, &right);
            }
            // L_KJ = S L_JJ⁻ᵀ = V D_J^-½ with V = S L̃_J⁻ᵀ; L_KJ L_KJᵀ = V D_J⁻¹ Vᵀ, taken from
            // V so that the next pivots do not wait on D_J's square roots.
            let d = &blocks[j];
            let [n10, n20, n21] = d.unit_inverse;
            let v = s.map(|[a, b, c]| [a, a * n10 + b, a * n20 + b * n21 + c]);
            for (i, v_row) in v.iter().enumerate() {
                for (l, target) in diagonal[i][..=i].iter_mut().enumerate() {
                    let weighted = v_row[0] * d.reciprocals[0] * v[l][0]
                        + v_row[1] * d.reciprocals[1] * v[l][1]
                        + v_row[2] * d.reciprocals[2] * v[l][2];
                    *target -= weighted;
                }
                let start = at(first, starts, 3 * k + i, 3 * j);
                for (target, (x, scale)) in values[start..start + 3]
                    .iter_mut()
                    .zip(v_row.iter().zip(d.inverse_roots))
                {
                    *target = x * scale;
                }
            }
        }
        let (factor, inverse) = diagonal_factor(&diagonal).map_err(|i| 3 * k + i)?;
        for (i, row) in factor.iter().enumerate() {
            let start = at(first, starts, 3 * k + i, 3 * k);
            values[start..=start + i].copy_from_slice(&row[..=i]);
        }
        blocks.push(inverse);
    }
    Ok(())
}

/// s ← s − a bᵀ.
fn subtract_product(s: &mut Block, a: &Block, b: &Block) {
    for (s_row, a_row) in s.iter_mut().zip(a) {
        for (target, b_row) in s_row.iter_mut().zip(b) {
            *target -= a_row[0] * b_row[0] + a_row[1] * b_row[1] + a_row[2] * b_row[2];
        }
    }
}

/// The Cholesky factor of a 3 × 3 block (its lower triangle) and what the substitutions keep
/// of it, or the row (0 to 2) whose pivot is not positive. The pivots by LDLᵀ (each waits on
/// the division before it), then L = L̃ D^½ and L⁻¹ = D^-½ L̃⁻¹.
fn diagonal_factor(s: &Block) -> Result<(Block, DiagonalBlock), usize> {
    let positive = |d: f64| d > 0.0 && d.is_finite();
    let d0 = s[0][0];
    if !positive(d0) {
        return Err(0);
    }
    let r0 = 1.0 / d0;
    let (u10, u20) = (s[1][0] * r0, s[2][0] * r0);
    let d1 = s[1][1] - s[1][0] * u10;
    if !positive(d1) {
        return Err(1);
    }
    let r1 = 1.0 / d1;
    let w21 = s[2][1] - s[2][0] * u10;
    let u21 = w21 * r1;
    let d2 = s[2][2] - s[2][0] * u20 - w21 * u21;
    if !positive(d2) {
        return Err(2);
    }
    let r2 = 1.0 / d2;
    let roots = [d0.sqrt(), d1.sqrt(), d2.sqrt()];
    // D^-½ = D^½ D⁻¹: one product where a square root would wait on the division.
    let inverse_roots = [roots[0] * r0, roots[1] * r1, roots[2] * r2];
    let factor = [
        [roots[0], 0.0, 0.0],
        [u10 * roots[0], roots[1], 0.0],
        [u20 * roots[0], u21 * roots[1], roots[2]],
    ];
    let (n10, n21) = (-u10, -u21);
    let n20 = u10 * u21 - u20;
    let block = DiagonalBlock {
        lower: [factor[1][0], factor[2][0], factor[2][1]],
        inverse_roots,
        unit_inverse: [n10, n20, n21],
        reciprocals: [r0, r1, r2],
    };
    Ok((factor, block))
}

/// Block row K's three rows left of its diagonal block (columns `first`..3K), the envelope's
/// rows laid out by triples.
fn left_of_diagonal<'v>(
    (first, starts, values): (&[usize], &[usize], &'v [f64]),
    k: usize,
) -> [&'v [f64]; 3] {
    let width = 3 * k - first[3 * k];
    let (a, b, c) = (starts[3 * k], starts[3 * k + 1], starts[3 * k + 2]);
    [
        &values[a..a + width],
        &values[b..b + width],
        &values[c..c + width],
    ]
}

/// y ← L⁻¹ y for each y of `ys` (of one length, the rows') for the factor by blocks
/// (`cholesky`) in `values`: the right-hand sides taken block by block together, so that their
/// chains of dependent blocks fill each other's waits. Each row as in the rows' substitution
/// (its entries summed in increasing column order), times its diagonal's reciprocal where
/// that divides by the diagonal.
pub fn forward<const N: usize>(
    envelope: (&[usize], &[usize], &[f64]),
    blocks: &[DiagonalBlock],
    mut ys: [&mut [f64]; N],
) {
    let rows = 3 * blocks.len();
    for (k, d) in blocks.iter().enumerate() {
        let from = envelope.0[3 * k];
        let [l0, l1, l2] = left_of_diagonal(envelope, k);
        let ([l10, l20, l21], [p0, p1, p2]) = (d.lower, d.inverse_roots);
        for y in ys.iter_mut() {
            let (done, rest) = y[..rows].split_at_mut(3 * k);
            let (mut s0, mut s1, mut s2) = (0.0, 0.0, 0.0);
            for (((x, a), b), c) in done[from..].iter().zip(l0).zip(l1).zip(l2) {
                s0 += a * x;
                s1 += b * x;
                s2 += c * x;
            }
            let y0 = (rest[0] - s0) * p0;
            let y1 = (rest[1] - (s1 + l10 * y0)) * p1;
            let y2 = (rest[2] - (s2 + l20 * y0 + l21 * y1)) * p2;
            (rest[0], rest[1], rest[2]) = (y0, y1, y2);
        }
    }
}

/// y ← L⁻ᵀ y for each y of `ys` (of one length, the rows') for the factor by blocks
/// (`cholesky`) in `values`, taken together as in `forward`, each row as in the rows'
/// substitution (the last row first, its entries subtracted from the rows before it).
pub fn backward<const N: usize>(
    envelope: (&[usize], &[usize], &[f64]),
    blocks: &[DiagonalBlock],
    mut ys: [&mut [f64]; N],
) {
    let rows = 3 * blocks.len();
    for (k, d) in blocks.iter().enumerate().rev() {
        let from = envelope.0[3 * k];
        let [l0, l1, l2] = left_of_diagonal(envelope, k);
        let ([l10, l20, l21], [p0, p1, p2]) = (d.lower, d.inverse_roots);
        for y in ys.iter_mut() {
            let (done, rest) = y[..rows].split_at_mut(3 * k);
            let x2 = rest[2] * p2;
            let x1 = (rest[1] - l21 * x2) * p1;
            let x0 = (rest[0] - l20 * x2 - l10 * x1) * p0;
            (rest[0], rest[1], rest[2]) = (x0, x1, x2);
            for (((target, a), b), c) in done[from..].iter_mut().zip(l0).zip(l1).zip(l2) {
                *target = *target - c * x2 - b * x1 - a * x0;
            }
        }
    }
}
