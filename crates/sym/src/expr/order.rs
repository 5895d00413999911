//! The canonical order of an expression's operands ([`Pool::cmp`]): how the
//! constructors sort the factors of a product and the terms of a sum, so that
//! equal expressions are built as one node, and names sort as people count.

use super::{ExprId, Node, Pool, Symbol};
use std::cmp::Ordering;

impl Pool {
    fn class(&self, id: ExprId) -> u8 {
        match self.node(id) {
            Node::Num(_) => 0,
            Node::Pi => 1,
            Node::Sym(_) => 2,
            Node::Func(..) | Node::Atan2(..) => 3,
            Node::Add(_) => 4,
            Node::Mul(_) => 5,
            Node::Pow(..) => 6,
        }
    }

    /// The total order that sorts factors of products: numbers, then symbols by
    /// rank, derivative order and name, then functions, then sums. Powers sort
    /// by their base, then by exponent.
    pub fn cmp(&self, a: ExprId, b: ExprId) -> Ordering {
        if a == b {
            return Ordering::Equal;
        }
        let (ba, ea) = self.base_exp(a);
        let (bb, eb) = self.base_exp(b);
        if ba != bb {
            return self.cmp_base(ba, bb);
        }
        self.cmp(ea, eb)
    }

    fn cmp_base(&self, a: ExprId, b: ExprId) -> Ordering {
        if a == b {
            return Ordering::Equal;
        }
        let (ca, cb) = (self.class(a), self.class(b));
        if ca != cb {
            return ca.cmp(&cb);
        }
        match (self.node(a), self.node(b)) {
            (Node::Num(x), Node::Num(y)) => x.to_f64().total_cmp(&y.to_f64()),
            (Node::Sym(x), Node::Sym(y)) => {
                let rank = |s: &Symbol| self.name_rank[s.name.0 as usize];
                rank(x)
                    .cmp(&rank(y))
                    .then(natural_cmp(self.name_str(x.name), self.name_str(y.name)))
                    .then(x.order.cmp(&y.order))
            }
            (Node::Func(f, x), Node::Func(g, y)) => f.cmp(g).then_with(|| self.cmp(*x, *y)),
            (Node::Func(..), Node::Atan2(..)) => Ordering::Less,
            (Node::Atan2(..), Node::Func(..)) => Ordering::Greater,
            (Node::Atan2(y1, x1), Node::Atan2(y2, x2)) => self.cmp(*y1, *y2).then_with(|| self.cmp(*x1, *x2)),
            (Node::Add(xs), Node::Add(ys)) | (Node::Mul(xs), Node::Mul(ys)) => {
                for (x, y) in xs.iter().zip(ys.iter()) {
                    let o = self.cmp(*x, *y);
                    if o != Ordering::Equal {
                        return o;
                    }
                }
                xs.len().cmp(&ys.len())
            }
            _ => a.cmp(&b),
        }
    }

    /// The order of terms in a sum: by their non-numeric factors compared from
    /// the most significant (last) one, so that terms in the same coordinates sit
    /// together; the constant last.
    pub(super) fn cmp_terms(&self, a: ExprId, b: ExprId) -> Ordering {
        let xs = self.term_factors(&a);
        let ys = self.term_factors(&b);
        for (x, y) in xs.iter().rev().zip(ys.iter().rev()) {
            let o = self.cmp(*x, *y);
            if o != Ordering::Equal {
                return o;
            }
        }
        xs.len().cmp(&ys.len()).then(a.cmp(&b))
    }

    /// The non-numeric factors of a term.
    fn term_factors<'a>(&'a self, id: &'a ExprId) -> &'a [ExprId] {
        match self.node(*id) {
            Node::Mul(fs) if self.as_number(fs[0]).is_some() => &fs[1..],
            Node::Mul(fs) => fs,
            _ => std::slice::from_ref(id),
        }
    }
}

/// Orders names as people count: `x2` before `x10` (digit runs compare as numbers).
pub(crate) fn natural_cmp(a: &str, b: &str) -> Ordering {
    let (mut a, mut b) = (a.as_bytes(), b.as_bytes());
    loop {
        match (a.first(), b.first()) {
            (None, None) => return Ordering::Equal,
            (None, Some(_)) => return Ordering::Less,
            (Some(_), None) => return Ordering::Greater,
            (Some(x), Some(y)) if x.is_ascii_digit() && y.is_ascii_digit() => {
                let da = a.iter().take_while(|c| c.is_ascii_digit()).count();
                let db = b.iter().take_while(|c| c.is_ascii_digit()).count();
                let (na, nb) = (&a[..da], &b[..db]);
                // Compare digit runs as numbers: strip leading zeros, then length, then digits.
                let trim = |n: &[u8]| -> usize { n.iter().take_while(|&&c| c == b'0').count() };
                let (ta, tb) = (&na[trim(na)..], &nb[trim(nb)..]);
                let o = ta.len().cmp(&tb.len()).then(ta.cmp(tb)).then(da.cmp(&db));
                if o != Ordering::Equal {
                    return o;
                }
                a = &a[da..];
                b = &b[db..];
            }
            (Some(x), Some(y)) => {
                if x != y {
                    return x.cmp(y);
                }
                a = &a[1..];
                b = &b[1..];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::natural_cmp;
    use std::cmp::Ordering;

    #[test]
    fn names_sort_as_people_count() {
        assert_eq!(natural_cmp("x2", "x10"), Ordering::Less);
        assert_eq!(natural_cmp("x10", "x9"), Ordering::Greater);
        assert_eq!(natural_cmp("m1", "m1"), Ordering::Equal);
        assert_eq!(natural_cmp("a", "b"), Ordering::Less);
        assert_eq!(natural_cmp("th1", "th"), Ordering::Greater);
        assert_eq!(natural_cmp("x01", "x1"), Ordering::Greater);
    }
}
