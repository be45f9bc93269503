//! Reading glTF accessors (glTF 2.0 spec §3.6 "Binary data storage") with every byte range
//! checked, instead of the `gltf` crate's reader, which indexes slices without checks
//! (a hostile file could make it panic).
//!
//! Supported: float vectors, normalised 8/16-bit integer vectors (texture coordinates), and
//! 8/16/32-bit unsigned index scalars, each dense or sparse (§3.6.2.3).

use gltf::accessor::{DataType, Dimensions};
use gltf::buffer::View;

/// Accessor elements bound to their bytes: component `c` of element `i` starts at byte
/// `i * stride + c * size(ty)` of `bytes` (the range was checked by [`bind`]).
struct Elements<'a> {
    bytes: &'a [u8],
    stride: usize,
    ty: DataType,
}

fn comp_size(ty: DataType) -> usize {
    match ty {
        DataType::I8 | DataType::U8 => 1,
        DataType::I16 | DataType::U16 => 2,
        DataType::U32 | DataType::F32 => 4,
    }
}

impl Elements<'_> {
    fn raw(&self, i: usize, c: usize) -> &[u8] {
        let s = comp_size(self.ty);
        let o = i * self.stride + c * s;
        &self.bytes[o..o + s]
    }

    /// Component `c` of element `i` as a float (normalised integers map to [0, 1] / [-1, 1] by
    /// the normalisation table of glTF 2.0 spec §3.11).
    fn f32(&self, i: usize, c: usize) -> f32 {
        let b = self.raw(i, c);
        match self.ty {
            DataType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            DataType::U8 => b[0] as f32 / 255.0,
            DataType::I8 => (b[0] as i8 as f32 / 127.0).max(-1.0),
            DataType::U16 => u16::from_le_bytes([b[0], b[1]]) as f32 / 65535.0,
            DataType::I16 => (i16::from_le_bytes([b[0], b[1]]) as f32 / 32767.0).max(-1.0),
            DataType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
        }
    }

    /// Scalar element `i` as an unsigned index.
    fn u32(&self, i: usize) -> u32 {
        self.uint(i, 0)
    }

    /// Component `c` of element `i` as an unsigned integer.
    fn uint(&self, i: usize, c: usize) -> u32 {
        let b = self.raw(i, c);
        match self.ty {
            DataType::U8 | DataType::I8 => b[0] as u32,
            DataType::U16 | DataType::I16 => u16::from_le_bytes([b[0], b[1]]) as u32,
            DataType::U32 | DataType::F32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        }
    }
}

/// Binds `count` elements at `offset` in `view`, checking every range against the buffer.
fn bind<'a>(
    buffers: &'a [Vec<u8>],
    view: &View,
    offset: usize,
    count: usize,
    ty: DataType,
    comps: usize,
    packed: bool,
) -> Result<Elements<'a>, String> {
    let elem = comp_size(ty) * comps;
    let stride = match view.stride() {
        Some(s) if !packed => s,
        _ => elem,
    };
    if stride < elem {
        return Err(format!(
            "buffer view {} has byteStride {stride} smaller than its {elem}-byte elements",
            view.index()
        ));
    }
    let data = &buffers[view.buffer().index()];
    let view_end = view
        .offset()
        .checked_add(view.length())
        .filter(|&e| e <= data.len())
        .ok_or_else(|| {
            format!(
                "buffer view {} (offset {}, length {}) exceeds buffer {} ({} bytes)",
                view.index(),
                view.offset(),
                view.length(),
                view.buffer().index(),
                data.len()
            )
        })?;
    let view_bytes = &data[view.offset()..view_end];
    let need = if count == 0 {
        Some(offset)
    } else {
        (count - 1)
            .checked_mul(stride)
            .and_then(|n| n.checked_add(elem))
            .and_then(|n| n.checked_add(offset))
    };
    match need {
        Some(n) if n <= view_bytes.len() => Ok(Elements {
            bytes: &view_bytes[offset..],
            stride,
            ty,
        }),
        _ => Err(format!(
            "{count} elements at offset {offset} do not fit in buffer view {} ({} bytes)",
            view.index(),
            view_bytes.len()
        )),
    }
}

/// Calls `f(i, elements, j)` for every element `i` of the accessor, where element `i` is element
/// `j` of `elements` (the dense data or the sparse substitutes). Elements of a sparse accessor
/// without a buffer view and not substituted are skipped (they are zero).
fn visit<'a>(
    acc: &gltf::Accessor,
    buffers: &'a [Vec<u8>],
    comps: usize,
    mut f: impl FnMut(usize, &Elements<'a>, usize),
) -> Result<(), String> {
    let (count, ty) = (acc.count(), acc.data_type());
    if let Some(view) = acc.view() {
        let e = bind(buffers, &view, acc.offset(), count, ty, comps, false)?;
        for i in 0..count {
            f(i, &e, i);
        }
    }
    if let Some(sparse) = acc.sparse() {
        let n = sparse.count();
        let idx = sparse.indices();
        let ity = match idx.index_type() {
            gltf::accessor::sparse::IndexType::U8 => DataType::U8,
            gltf::accessor::sparse::IndexType::U16 => DataType::U16,
            gltf::accessor::sparse::IndexType::U32 => DataType::U32,
        };
        let ie = bind(buffers, &idx.view(), idx.offset(), n, ity, 1, true)?;
        let vals = sparse.values();
        let ve = bind(buffers, &vals.view(), vals.offset(), n, ty, comps, true)?;
        for j in 0..n {
            let i = ie.u32(j) as usize;
            if i >= count {
                return Err(format!("sparse index {i} out of range ({count} elements)"));
            }
            f(i, &ve, j);
        }
    }
    Ok(())
}

/// Most elements of an accessor with no buffer view (all zero unless sparse-substituted): such
/// a count costs memory without costing file bytes, so it is bounded.
const MAX_VIEWLESS_ELEMENTS: usize = 1 << 24;

/// Checks, before anything is allocated, that the accessor's elements fit in its buffer.
fn precheck(acc: &gltf::Accessor, buffers: &[Vec<u8>], comps: usize) -> Result<(), String> {
    match acc.view() {
        Some(view) => bind(
            buffers,
            &view,
            acc.offset(),
            acc.count(),
            acc.data_type(),
            comps,
            false,
        )
        .map(|_| ()),
        None if acc.count() <= MAX_VIEWLESS_ELEMENTS => Ok(()),
        None => Err(format!(
            "{} elements without a buffer view (at most {MAX_VIEWLESS_ELEMENTS})",
            acc.count()
        )),
    }
    .map_err(|m| format!("accessor {}: {m}", acc.index()))
}

/// Reads a float vector accessor of `N` components (`VEC2`/`VEC3`). `allow_normalized`
/// accepts normalised 8/16-bit integers as well (texture coordinates).
pub(crate) fn read_vec<const N: usize>(
    acc: &gltf::Accessor,
    buffers: &[Vec<u8>],
    allow_normalized: bool,
) -> Result<Vec<[f32; N]>, String> {
    let dims_ok = matches!(
        (acc.dimensions(), N),
        (Dimensions::Vec2, 2) | (Dimensions::Vec3, 3) | (Dimensions::Vec4, 4)
    );
    let ty_ok = acc.data_type() == DataType::F32
        || (allow_normalized
            && acc.normalized()
            && matches!(acc.data_type(), DataType::U8 | DataType::U16));
    if !dims_ok || !ty_ok {
        return Err(format!(
            "accessor {} is {:?} {:?}{}, expected VEC{N} of floats",
            acc.index(),
            acc.dimensions(),
            acc.data_type(),
            if acc.normalized() { " normalized" } else { "" }
        ));
    }
    precheck(acc, buffers, N)?;
    let mut out = vec![[0.0f32; N]; acc.count()];
    visit(acc, buffers, N, |i, e, j| {
        for (c, v) in out[i].iter_mut().enumerate() {
            *v = e.f32(j, c);
        }
    })
    .map_err(|m| format!("accessor {}: {m}", acc.index()))?;
    Ok(out)
}

/// Reads an index accessor (`SCALAR` of unsigned 8/16/32-bit integers).
pub(crate) fn read_indices(acc: &gltf::Accessor, buffers: &[Vec<u8>]) -> Result<Vec<u32>, String> {
    if acc.dimensions() != Dimensions::Scalar
        || !matches!(
            acc.data_type(),
            DataType::U8 | DataType::U16 | DataType::U32
        )
    {
        return Err(format!(
            "index accessor {} is {:?} {:?}, expected SCALAR of unsigned integers",
            acc.index(),
            acc.dimensions(),
            acc.data_type()
        ));
    }
    precheck(acc, buffers, 1)?;
    let mut out = vec![0u32; acc.count()];
    visit(acc, buffers, 1, |i, e, j| out[i] = e.u32(j))
        .map_err(|m| format!("accessor {}: {m}", acc.index()))?;
    Ok(out)
}

/// Number of components of an element of `dims`.
pub(crate) fn components(dims: Dimensions) -> usize {
    match dims {
        Dimensions::Scalar => 1,
        Dimensions::Vec2 => 2,
        Dimensions::Vec3 => 3,
        Dimensions::Vec4 | Dimensions::Mat2 => 4,
        Dimensions::Mat3 => 9,
        Dimensions::Mat4 => 16,
    }
}

/// Reads any float-valued accessor of shape `dims` as `count * components(dims)` floats
/// (element-major). `accept(ty, normalized)` says which component types the semantic allows
/// (glTF 2.0 spec §3.7.2.1 for vertex attributes, §3.11 for animation samplers); normalised
/// integers map to [0, 1] / [-1, 1]. `MAT4` of floats has no column padding; matrices of
/// smaller types (padded columns) are not supported by this reader.
pub(crate) fn read_floats(
    acc: &gltf::Accessor,
    buffers: &[Vec<u8>],
    dims: Dimensions,
    accept: impl Fn(DataType, bool) -> bool,
) -> Result<Vec<f32>, String> {
    let n = components(dims);
    let padded = matches!(dims, Dimensions::Mat2 | Dimensions::Mat3)
        || (dims == Dimensions::Mat4 && acc.data_type() != DataType::F32);
    if acc.dimensions() != dims || !accept(acc.data_type(), acc.normalized()) || padded {
        return Err(format!(
            "accessor {} is {:?} {:?}{}, not an allowed {dims:?} type here",
            acc.index(),
            acc.dimensions(),
            acc.data_type(),
            if acc.normalized() { " normalized" } else { "" }
        ));
    }
    precheck(acc, buffers, n)?;
    let mut out = vec![0.0f32; acc.count() * n];
    visit(acc, buffers, n, |i, e, j| {
        for (c, v) in out[i * n..(i + 1) * n].iter_mut().enumerate() {
            *v = e.f32(j, c);
        }
    })
    .map_err(|m| format!("accessor {}: {m}", acc.index()))?;
    Ok(out)
}

/// Reads a `VEC4` of unsigned, not normalised 8/16-bit integers (skin joint indices,
/// glTF 2.0 spec §3.7.3.3) as `count` quadruples.
pub(crate) fn read_uvec4(
    acc: &gltf::Accessor,
    buffers: &[Vec<u8>],
) -> Result<Vec<[u32; 4]>, String> {
    if acc.dimensions() != Dimensions::Vec4
        || acc.normalized()
        || !matches!(acc.data_type(), DataType::U8 | DataType::U16)
    {
        return Err(format!(
            "accessor {} is {:?} {:?}, expected VEC4 of unsigned 8/16-bit integers",
            acc.index(),
            acc.dimensions(),
            acc.data_type()
        ));
    }
    precheck(acc, buffers, 4)?;
    let mut out = vec![[0u32; 4]; acc.count()];
    visit(acc, buffers, 4, |i, e, j| {
        for (c, v) in out[i].iter_mut().enumerate() {
            *v = e.uint(j, c);
        }
    })
    .map_err(|m| format!("accessor {}: {m}", acc.index()))?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalised_components_map_to_unit_range() {
        let bytes = [255u8, 0, 0x80, 0x7f, 0xff, 0xff];
        let u8e = Elements {
            bytes: &bytes,
            stride: 2,
            ty: DataType::U8,
        };
        assert_eq!(u8e.f32(0, 0), 1.0);
        assert_eq!(u8e.f32(0, 1), 0.0);
        let u16e = Elements {
            bytes: &bytes[4..],
            stride: 2,
            ty: DataType::U16,
        };
        assert_eq!(u16e.f32(0, 0), 1.0);
        assert_eq!(u16e.u32(0), 65535);
    }
}
