//! Linear systems of expressions solved symbolically: M's blocks (the
//! coordinates it couples), the adjugate over the determinant for a small
//! block, and elimination with pivots that are proven nonzero for larger ones.

use super::MAX_PRINTED_TREE;
use sym::{ExprId, Pool, Symbol};

/// The size of the largest block of coordinates coupled by M.
pub(super) fn largest_block(pool: &Pool, m: &[Vec<ExprId>]) -> usize {
    blocks(pool, m).iter().map(Vec::len).max().unwrap_or(0)
}

/// Solves M v = r symbolically for the Legendre transform, block by block:
/// coordinates that M couples form a block; 1×1 blocks divide, 2×2 and 3×3
/// blocks use the adjugate over the (simplified) determinant, and larger
/// blocks use Gaussian elimination without pivoting (M is positive definite)
/// whose intermediate results stay shared in the DAG.
pub(super) fn solve_symbolic(
    pool: &mut Pool,
    m: &[Vec<ExprId>],
    r: &[ExprId],
    is_var: &dyn Fn(Symbol) -> bool,
) -> Option<Vec<ExprId>> {
    let n = r.len();
    let mut v = vec![pool.zero(); n];
    for idx in blocks(pool, m) {
        let k = idx.len();
        let a: Vec<Vec<ExprId>> = idx.iter().map(|&i| idx.iter().map(|&j| m[i][j]).collect()).collect();
        let rhs: Vec<ExprId> = idx.iter().map(|&i| r[i]).collect();
        let sol = match k {
            1 => vec![pool.div(rhs[0], a[0][0])],
            2 | 3 => adjugate_solve(pool, &a, &rhs, is_var),
            _ => elimination_solve(pool, a, rhs)?,
        };
        for (pos, &i) in idx.iter().enumerate() {
            v[i] = sol[pos];
        }
    }
    Some(v)
}

/// The groups of coordinates that M couples (connected components of its
/// nonzero pattern), each in ascending order.
pub(super) fn blocks(pool: &Pool, m: &[Vec<ExprId>]) -> Vec<Vec<usize>> {
    let n = m.len();
    let mut block_of: Vec<usize> = (0..n).collect();
    fn find(b: &mut [usize], i: usize) -> usize {
        let mut i = i;
        while b[i] != i {
            b[i] = b[b[i]];
            i = b[i];
        }
        i
    }
    for i in 0..n {
        for j in 0..n {
            if i != j && !pool.is_zero(m[i][j]) {
                let (a, b) = (find(&mut block_of, i), find(&mut block_of, j));
                block_of[a] = b;
            }
        }
    }
    let mut blocks: Vec<Vec<usize>> = Vec::new();
    let mut root_index: Vec<Option<usize>> = vec![None; n];
    for i in 0..n {
        let root = find(&mut block_of, i);
        match root_index[root] {
            Some(k) => blocks[k].push(i),
            None => {
                root_index[root] = Some(blocks.len());
                blocks.push(vec![i]);
            }
        }
    }
    blocks
}

pub(super) fn adjugate_solve(
    pool: &mut Pool,
    a: &[Vec<ExprId>],
    r: &[ExprId],
    is_var: &dyn Fn(Symbol) -> bool,
) -> Vec<ExprId> {
    let k = a.len();
    let (adj, det) = adjugate(pool, a, is_var);
    (0..k)
        .map(|i| {
            let terms: Vec<ExprId> = (0..k).map(|j| pool.mul2(adj[i][j], r[j])).collect();
            let num = pool.add(&terms);
            let num = pool.simplify_in(num, is_var);
            pool.div(num, det)
        })
        .collect()
}

/// The adjugate (entries simplified) and the simplified determinant of a 2×2 or 3×3 matrix.
pub(super) fn adjugate(
    pool: &mut Pool,
    a: &[Vec<ExprId>],
    is_var: &dyn Fn(Symbol) -> bool,
) -> (Vec<Vec<ExprId>>, ExprId) {
    let k = a.len();
    let minor = |pool: &mut Pool, rows: [usize; 2], cols: [usize; 2]| {
        let x = pool.mul2(a[rows[0]][cols[0]], a[rows[1]][cols[1]]);
        let y = pool.mul2(a[rows[0]][cols[1]], a[rows[1]][cols[0]]);
        pool.sub(x, y)
    };
    // adj[i][j] = cofactor C_ji.
    let mut adj = vec![vec![pool.zero(); k]; k];
    let det;
    if k == 2 {
        adj[0][0] = a[1][1];
        adj[1][1] = a[0][0];
        adj[0][1] = pool.neg(a[0][1]);
        adj[1][0] = pool.neg(a[1][0]);
        det = minor(pool, [0, 1], [0, 1]);
    } else {
        let others = |i: usize| -> [usize; 2] {
            match i {
                0 => [1, 2],
                1 => [0, 2],
                _ => [0, 1],
            }
        };
        // M is symmetric, and so is its adjugate.
        for i in 0..3 {
            for j in i..3 {
                let c = minor(pool, others(j), others(i));
                let c = if (i + j) % 2 == 0 { c } else { pool.neg(c) };
                adj[i][j] = pool.simplify_in(c, is_var);
                adj[j][i] = adj[i][j];
            }
        }
        let terms: Vec<ExprId> = (0..3).map(|j| pool.mul2(a[0][j], adj[j][0])).collect();
        det = pool.add(&terms);
    }
    let det = pool.simplify_in(det, is_var);
    (adj, det)
}

/// Gaussian elimination; None as soon as a pivot is too long to print, since
/// the solution divides by every pivot (a dense block of a pendulum with four
/// links gets there within a few columns, long before the O(k³) work is done).
pub(super) fn elimination_solve(pool: &mut Pool, mut a: Vec<Vec<ExprId>>, mut r: Vec<ExprId>) -> Option<Vec<ExprId>> {
    let k = r.len();
    for col in 0..k {
        let piv = a[col][col];
        if pool.tree_size(piv) > MAX_PRINTED_TREE {
            return None;
        }
        for row in col + 1..k {
            if pool.is_zero(a[row][col]) {
                continue;
            }
            let factor = pool.div(a[row][col], piv);
            for c in col..k {
                let x = pool.mul2(factor, a[col][c]);
                a[row][c] = pool.sub(a[row][c], x);
            }
            let x = pool.mul2(factor, r[col]);
            r[row] = pool.sub(r[row], x);
        }
    }
    let mut v = vec![pool.zero(); k];
    for row in (0..k).rev() {
        let mut acc = r[row];
        for c in row + 1..k {
            let x = pool.mul2(a[row][c], v[c]);
            acc = pool.sub(acc, x);
        }
        v[row] = pool.div(acc, a[row][row]);
    }
    Some(v)
}
