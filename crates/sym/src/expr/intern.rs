//! The arena's hash-consing: every node is stored once, found again by its
//! hash in an open-addressing table ([`Pool::lookup`]); a new node is stored
//! with its hash, its tree size and the Bloom filter of its symbols.

use super::{ExprId, Node, Pool, Symbol};
use rustc_hash::FxHasher;
use std::hash::{Hash, Hasher};

/// An empty slot of the intern table.
pub(super) const EMPTY: u32 = u32::MAX;

/// Which n-ary node an operand slice is looked up as.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub(super) enum Seq {
    Add,
    Mul,
}

pub(super) fn hash_seq(kind: Seq, items: &[ExprId]) -> u64 {
    let mut h = FxHasher::default();
    kind.hash(&mut h);
    items.hash(&mut h);
    h.finish()
}

fn hash_node(node: &Node) -> u64 {
    match node {
        Node::Add(ts) => hash_seq(Seq::Add, ts),
        Node::Mul(fs) => hash_seq(Seq::Mul, fs),
        other => {
            let mut h = FxHasher::default();
            other.hash(&mut h);
            h.finish()
        }
    }
}

/// Where a hash starts probing in a table of `mask + 1` slots (the high half of
/// a Fibonacci product: well mixed even when the hash's low bits are not).
fn home_slot(hash: u64, mask: usize) -> usize {
    (hash.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 32) as usize & mask
}

/// The Bloom-filter bit of a symbol.
fn symbol_bit(s: Symbol) -> u64 {
    let h = (u64::from(s.name.0) << 8 | u64::from(s.order)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    1 << (h >> 58)
}

impl Pool {
    pub(super) fn intern(&mut self, node: Node) -> ExprId {
        self.work += 1;
        let hash = hash_node(&node);
        match self.lookup(hash, |n| *n == node) {
            Ok(id) => id,
            Err(slot) => self.insert(node, hash, slot),
        }
    }

    /// Interns the sum or product of `items` (already canonical), allocating
    /// only when it is new.
    pub(super) fn intern_seq(&mut self, kind: Seq, items: &[ExprId]) -> ExprId {
        self.work += 1 + items.len() as u64;
        let hash = hash_seq(kind, items);
        let found = self.lookup(hash, |n| match (kind, n) {
            (Seq::Add, Node::Add(ts)) => **ts == *items,
            (Seq::Mul, Node::Mul(fs)) => **fs == *items,
            _ => false,
        });
        match found {
            Ok(id) => id,
            Err(slot) => {
                let items: Box<[ExprId]> = items.into();
                let node = if kind == Seq::Add { Node::Add(items) } else { Node::Mul(items) };
                self.insert(node, hash, slot)
            }
        }
    }

    /// The id of the node with this hash for which `eq` holds, or the empty
    /// slot where it would go.
    pub(super) fn lookup(&self, hash: u64, eq: impl Fn(&Node) -> bool) -> Result<ExprId, usize> {
        let mask = self.table.len() - 1;
        let mut slot = home_slot(hash, mask);
        loop {
            let id = self.table[slot];
            if id == EMPTY {
                return Err(slot);
            }
            if self.hashes[id as usize] == hash && eq(&self.nodes[id as usize]) {
                return Ok(ExprId(id));
            }
            slot = (slot + 1) & mask;
        }
    }

    /// Stores a new node at `slot` of the table (from a failed [`Pool::lookup`]).
    pub(super) fn insert(&mut self, node: Node, hash: u64, slot: usize) -> ExprId {
        let raw =
            u32::try_from(self.nodes.len()).ok().filter(|&i| i != EMPTY).expect("more than 2^32 expression nodes");
        let sz = |c: &ExprId| self.tree_sizes[c.index()];
        let size = 1u64.saturating_add(match &node {
            Node::Num(_) | Node::Pi | Node::Sym(_) => 0,
            Node::Add(ts) | Node::Mul(ts) => ts.iter().map(sz).fold(0u64, u64::saturating_add),
            Node::Pow(a, b) | Node::Atan2(a, b) => sz(a).saturating_add(sz(b)),
            Node::Func(_, a) => sz(a),
        });
        let mk = |c: &ExprId| self.sym_masks[c.index()];
        let mask = match &node {
            Node::Num(_) | Node::Pi => 0,
            Node::Sym(s) => symbol_bit(*s),
            Node::Add(ts) | Node::Mul(ts) => ts.iter().map(mk).fold(0, |a, b| a | b),
            Node::Pow(a, b) | Node::Atan2(a, b) => mk(a) | mk(b),
            Node::Func(_, a) => mk(a),
        };
        self.tree_sizes.push(size);
        self.sym_masks.push(mask);
        self.hashes.push(hash);
        self.nodes.push(node);
        self.table[slot] = raw;
        if self.nodes.len() * 2 > self.table.len() {
            self.grow_table();
        }
        ExprId(raw)
    }

    fn grow_table(&mut self) {
        let mut table = vec![EMPTY; self.table.len() * 2];
        let mask = table.len() - 1;
        for (id, &hash) in self.hashes.iter().enumerate() {
            let mut slot = home_slot(hash, mask);
            while table[slot] != EMPTY {
                slot = (slot + 1) & mask;
            }
            table[slot] = id as u32;
        }
        self.table = table;
    }
}
