//! The packets of one tile held side by side for the sweep (`cast/setup/sweep.rs`): each
//! packet's ray directions, best `1/t` and triangle per lane, its `|d|_inf`, exit depth and
//! closest-hit limit, its affine box ([`super::affine::PacketBox::scalars`]) and its
//! reciprocal-direction interval in rows of sixteen packets.
//! Reused from tile to tile (per thread, in [`super::TileTris`]): no allocation once grown.

use crate::cast::packet::MAX_LANES;

/// One packet's rays and closest hits so far, on five cache lines.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct Packet {
    /// Directions per axis, sixteen lanes.
    pub d: [[f32; MAX_LANES]; 3],
    /// Best `1/t` so far per lane (0: no hit).
    pub best: [f32; MAX_LANES],
    /// Triangle of the best hit per lane (`u32::MAX`: none).
    pub tri: [u32; MAX_LANES],
}

/// A tile's packets (module docs). The exit depths and box rows by row `p / 16`, lane
/// `p % 16`, padded.
#[derive(Clone, Debug, Default)]
pub struct TilePackets {
    pub packets: Vec<Packet>,
    /// The largest `|d|_inf` over every packet's lanes (the scale of the edge band: an upper
    /// bound of each packet's own, so each band stays conservative).
    pub dinf: f32,
    /// The packet's exit depth (the largest depth of its lanes' hits along the beam's axis)
    /// once every lane has a hit; `+inf` before.
    pub exit: Vec<f32>,
    /// The largest closest-hit limit `1/best` of the packet's lanes (`+inf` while a lane has
    /// no hit): the far end of its run-box test.
    pub lim: Vec<f32>,
    /// The box rows: `[xc, yc, rx, ry, ka, kb]`, sixteen packets per row.
    pub boxes: Vec<[[f32; 16]; 6]>,
    /// The interval rows: per axis bounds of the reciprocal directions of the packet's lanes,
    /// `[i0.x, i0.y, i0.z, i1.x, i1.y, i1.z]`, where they are finite and of one sign; both 0
    /// on an axis where not (the run-box test then passes every box).
    pub intervals: Vec<[[f32; 16]; 6]>,
    /// Packets whose direction range is their lanes' own (outside the film frame's region):
    /// `(packet, smallest, largest)` per axis in lanes 0-2.
    pub own_range: Vec<(u32, glam::Vec4, glam::Vec4)>,
}

impl Packet {
    /// A packet of directions `d` without hits: every best `1/t` 0, every triangle none.
    #[inline(always)]
    pub fn fresh(d: [[f32; MAX_LANES]; 3]) -> Self {
        Self {
            d,
            best: [0.0; MAX_LANES],
            tri: [u32::MAX; MAX_LANES],
        }
    }
}

impl TilePackets {
    /// Room for `n` packets, every exit depth and limit `+inf`. The packets keep whatever
    /// they held (one pass fewer over the tile's packets): the caller writes each of the `n`
    /// whole, [`Packet::fresh`].
    pub fn reset(&mut self, n: usize) {
        if self.packets.len() < n {
            self.packets.resize(n, Packet::fresh([[0.0; MAX_LANES]; 3]));
        } else {
            self.packets.truncate(n);
        }
        self.dinf = 0.0;
        self.exit.clear();
        self.exit.resize(n.next_multiple_of(16), f32::INFINITY);
        self.lim.clear();
        self.lim.resize(n.next_multiple_of(16), f32::INFINITY);
        self.boxes.resize(n.div_ceil(16), [[0.0; 16]; 6]);
        self.intervals.resize(n.div_ceil(16), [[0.0; 16]; 6]);
        self.own_range.clear();
    }
}
