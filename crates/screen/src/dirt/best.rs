//! The answer of one DIRT ray as the bucket tracing builds it (Vardis et al. 2017,
//! Algorithm 1 line 15: "new best hit found") and the work counters of its walks.
//!
//! **Invariant:** [`Best::offer`] keeps the smallest `t`, ties to the lower triangle id, so the
//! answer does not depend on the order in which triangles are offered.

/// The closest hit so far.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Best {
    pub t: f32,
    pub prim: u32,
    pub u: f32,
    pub v: f32,
}

impl Best {
    pub const NONE: Best = Best {
        t: f32::INFINITY,
        prim: u32::MAX,
        u: 0.0,
        v: 0.0,
    };

    #[inline(always)]
    pub fn found(&self) -> bool {
        self.prim != u32::MAX
    }

    /// Exclusive upper bound for the next test: a triangle at exactly `t` must still be tested
    /// for the tie-break.
    #[inline(always)]
    pub fn limit(&self, t_max: f32) -> f32 {
        if self.found() {
            self.t.next_up().min(t_max)
        } else {
            t_max
        }
    }

    #[inline(always)]
    pub fn offer(&mut self, t: f32, prim: u32, u: f32, v: f32) {
        if t < self.t || (t == self.t && prim < self.prim) {
            *self = Best { t, prim, u, v };
        }
    }
}

/// Work counters of the walks of one ray.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct DirtCounters {
    /// Views entered.
    pub views: u64,
    /// Mip texels visited (all levels).
    pub texels: u64,
    /// Level-0 cells whose buckets were traced.
    pub cells: u64,
    /// Buckets traced.
    pub buckets: u64,
    /// Ray-triangle tests.
    pub tests: u64,
    /// Walks cut by their step bound.
    pub truncated: u64,
}

impl std::ops::AddAssign for DirtCounters {
    fn add_assign(&mut self, o: Self) {
        self.views += o.views;
        self.texels += o.texels;
        self.cells += o.cells;
        self.buckets += o.buckets;
        self.tests += o.tests;
        self.truncated += o.truncated;
    }
}
