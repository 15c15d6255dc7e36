//! Bounds-checked accessor reads (glTF 2.0 spec, section 3.6).
//!
//! The `gltf` crate's reader trusts the document (it `debug_assert!`s on
//! strides and underflows on `count - 1`), so glint reads accessors itself:
//! every byte range is checked against the bytes actually loaded before
//! anything is allocated, so a document claiming billions of elements over a
//! tiny buffer is an error, not an allocation.

use gltf::json::accessor::{ComponentType, Type};
use gltf::json::validation::Checked;
use gltf::json::{Accessor, Root};

/// Upper bound on the element count of an accessor with no buffer view (its
/// elements are implicit zeros, so no buffer bounds it): 2^22, at most 64 MB.
pub const MAX_IMPLICIT_ELEMENTS: u64 = 1 << 22;

fn component_size(c: ComponentType) -> u64 {
    match c {
        ComponentType::I8 | ComponentType::U8 => 1,
        ComponentType::I16 | ComponentType::U16 => 2,
        ComponentType::U32 | ComponentType::F32 => 4,
    }
}

fn components(t: Type) -> usize {
    match t {
        Type::Scalar => 1,
        Type::Vec2 => 2,
        Type::Vec3 => 3,
        Type::Vec4 => 4,
        Type::Mat2 => 4,
        Type::Mat3 => 9,
        Type::Mat4 => 16,
    }
}

fn type_name(t: Type) -> &'static str {
    match t {
        Type::Scalar => "SCALAR",
        Type::Vec2 => "VEC2",
        Type::Vec3 => "VEC3",
        Type::Vec4 => "VEC4",
        Type::Mat2 => "MAT2",
        Type::Mat3 => "MAT3",
        Type::Mat4 => "MAT4",
    }
}

/// One component as f32: floats as stored; integers normalised when the
/// accessor says so (glTF 2.0 spec, section 3.11, "normalized" formulas),
/// else converted as values.
fn decode(c: ComponentType, normalized: bool, b: &[u8]) -> f32 {
    match c {
        ComponentType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        ComponentType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
        ComponentType::I8 => {
            let v = b[0] as i8 as f32;
            if normalized { (v / 127.0).max(-1.0) } else { v }
        }
        ComponentType::U8 => {
            let v = b[0] as f32;
            if normalized { v / 255.0 } else { v }
        }
        ComponentType::I16 => {
            let v = i16::from_le_bytes([b[0], b[1]]) as f32;
            if normalized {
                (v / 32767.0).max(-1.0)
            } else {
                v
            }
        }
        ComponentType::U16 => {
            let v = u16::from_le_bytes([b[0], b[1]]) as f32;
            if normalized { v / 65535.0 } else { v }
        }
    }
}

fn decode_index(c: ComponentType, b: &[u8]) -> Option<u32> {
    match c {
        ComponentType::U8 => Some(b[0] as u32),
        ComponentType::U16 => Some(u16::from_le_bytes([b[0], b[1]]) as u32),
        ComponentType::U32 => Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        _ => None,
    }
}

/// A checked strided view into a buffer: element `i` starts at
/// `data[i * stride..]` and has `elem` bytes.
struct Strided<'a> {
    data: &'a [u8],
    stride: usize,
}

/// Where an accessor's (or a sparse part's) elements lie in a buffer view.
struct Span {
    view: usize,
    /// Byte offset into the view.
    offset: u64,
    count: u64,
    /// Bytes per element.
    elem: u64,
    /// Component size: offsets and strides must be multiples of it.
    align: u64,
    /// Whether the view's byteStride applies (sparse parts are packed).
    allow_stride: bool,
}

/// Resolve a [`Span`], checking every range in 64-bit arithmetic against the
/// loaded bytes.
fn strided<'a>(root: &Root, buffers: &'a [Vec<u8>], span: Span) -> Result<Strided<'a>, String> {
    let Span {
        view,
        offset,
        count,
        elem,
        align,
        allow_stride,
    } = span;
    let v = root
        .buffer_views
        .get(view)
        .ok_or_else(|| format!("buffer view {view} does not exist"))?;
    let data = buffers.get(v.buffer.value()).ok_or_else(|| {
        format!(
            "buffer view {view}: buffer {} does not exist",
            v.buffer.value()
        )
    })?;
    let v_off = v.byte_offset.map_or(0, |o| o.0);
    let v_len = v.byte_length.0;
    let v_end = v_off
        .checked_add(v_len)
        .filter(|&e| e <= data.len() as u64)
        .ok_or_else(|| {
            format!(
                "buffer view {view} (bytes {v_off}..+{v_len}) runs past the end of buffer {} ({} bytes)",
                v.buffer.value(),
                data.len()
            )
        })?;
    let stride = match v.byte_stride {
        Some(s) if allow_stride => s.0 as u64,
        Some(_) => {
            return Err(format!(
                "buffer view {view} must not have a byteStride here"
            ));
        }
        None => elem,
    };
    if stride < elem {
        return Err(format!(
            "buffer view {view}: byteStride {stride} is smaller than the {elem}-byte element"
        ));
    }
    if offset % align != 0 || stride % align != 0 {
        return Err(format!(
            "buffer view {view}: offset {offset} or stride {stride} is not a multiple of the component size {align}"
        ));
    }
    let needed = if count == 0 {
        Some(0)
    } else {
        (count - 1)
            .checked_mul(stride)
            .and_then(|x| x.checked_add(elem))
            .and_then(|x| x.checked_add(offset))
    };
    match needed {
        Some(n) if n <= v_len => {
            let start = (v_off + offset) as usize;
            let end = if count == 0 {
                start
            } else {
                (v_off + n) as usize
            };
            debug_assert!(end as u64 <= v_end);
            Ok(Strided {
                data: &data[start.min(end)..end],
                stride: stride as usize,
            })
        }
        _ => Err(format!(
            "{count} elements of {elem} bytes (stride {stride}) at offset {offset} do not fit in buffer view {view} ({v_len} bytes)"
        )),
    }
}

impl Strided<'_> {
    fn elem(&self, i: usize) -> &[u8] {
        &self.data[i * self.stride..]
    }
}

fn checked<T: Copy>(c: &Checked<T>, what: &str) -> Result<T, String> {
    match c {
        Checked::Valid(v) => Ok(*v),
        Checked::Invalid => Err(format!("invalid {what}")),
    }
}

fn get(root: &Root, index: usize) -> Result<&Accessor, String> {
    root.accessors
        .get(index)
        .ok_or_else(|| format!("accessor {index} does not exist"))
}

/// Read accessor `index` as `N`-component float vectors (any component type,
/// normalised integers mapped to [0, 1] or [-1, 1]), sparse substitution
/// applied.
pub fn read_vec<const N: usize>(
    root: &Root,
    buffers: &[Vec<u8>],
    index: usize,
) -> Result<Vec<[f32; N]>, String> {
    read_vec_inner(root, buffers, index).map_err(|e| format!("accessor {index}: {e}"))
}

fn read_vec_inner<const N: usize>(
    root: &Root,
    buffers: &[Vec<u8>],
    index: usize,
) -> Result<Vec<[f32; N]>, String> {
    let acc = get(root, index)?;
    let ty = checked(&acc.type_, "type")?;
    let comp = checked(&acc.component_type, "componentType")?.0;
    if components(ty) != N || matches!(ty, Type::Mat2) {
        return Err(format!(
            "type is {}, expected a {N}-component vector",
            type_name(ty)
        ));
    }
    let csize = component_size(comp);
    let elem = csize * N as u64;
    let count = acc.count.0;
    let mut out: Vec<[f32; N]> = match acc.buffer_view {
        Some(view) => {
            let s = strided(
                root,
                buffers,
                Span {
                    view: view.value(),
                    offset: acc.byte_offset.map_or(0, |o| o.0),
                    count,
                    elem,
                    align: csize,
                    allow_stride: true,
                },
            )?;
            (0..count as usize)
                .map(|i| {
                    let e = s.elem(i);
                    std::array::from_fn(|j| decode(comp, acc.normalized, &e[j * csize as usize..]))
                })
                .collect()
        }
        None => {
            if count > MAX_IMPLICIT_ELEMENTS {
                return Err(format!(
                    "{count} elements without a buffer view (at most {MAX_IMPLICIT_ELEMENTS})"
                ));
            }
            vec![[0.0; N]; count as usize]
        }
    };
    if let Some(sparse) = &acc.sparse {
        let n = sparse.count.0;
        let idx_comp = checked(&sparse.indices.component_type, "sparse index type")?.0;
        let isize = component_size(idx_comp);
        let idx = strided(
            root,
            buffers,
            Span {
                view: sparse.indices.buffer_view.value(),
                offset: sparse.indices.byte_offset.0,
                count: n,
                elem: isize,
                align: isize,
                allow_stride: false,
            },
        )
        .map_err(|e| format!("sparse indices: {e}"))?;
        let vals = strided(
            root,
            buffers,
            Span {
                view: sparse.values.buffer_view.value(),
                offset: sparse.values.byte_offset.0,
                count: n,
                elem,
                align: csize,
                allow_stride: false,
            },
        )
        .map_err(|e| format!("sparse values: {e}"))?;
        for k in 0..n as usize {
            let i = decode_index(idx_comp, idx.elem(k))
                .ok_or("sparse indices must be unsigned integers")? as usize;
            let slot = out
                .get_mut(i)
                .ok_or_else(|| format!("sparse index {i} is out of range ({count} elements)"))?;
            let e = vals.elem(k);
            *slot = std::array::from_fn(|j| decode(comp, acc.normalized, &e[j * csize as usize..]));
        }
    }
    Ok(out)
}

/// Read an index accessor (unsigned SCALAR, glTF 2.0 spec section 3.7.2.1).
pub fn read_indices(root: &Root, buffers: &[Vec<u8>], index: usize) -> Result<Vec<u32>, String> {
    let inner = || -> Result<Vec<u32>, String> {
        let acc = get(root, index)?;
        let comp = checked(&acc.component_type, "componentType")?.0;
        let ty = checked(&acc.type_, "type")?;
        if ty != Type::Scalar
            || !matches!(
                comp,
                ComponentType::U8 | ComponentType::U16 | ComponentType::U32
            )
        {
            return Err("indices must be unsigned byte, short or int SCALARs".into());
        }
        if acc.sparse.is_some() {
            return Err("sparse index accessors are not supported".into());
        }
        let csize = component_size(comp);
        let count = acc.count.0;
        // No buffer view: the elements are zeros (glTF 2.0 spec 3.6.2.3).
        let Some(view) = acc.buffer_view else {
            if count > MAX_IMPLICIT_ELEMENTS {
                return Err(format!(
                    "{count} elements without a buffer view (at most {MAX_IMPLICIT_ELEMENTS})"
                ));
            }
            return Ok(vec![0; count as usize]);
        };
        let s = strided(
            root,
            buffers,
            Span {
                view: view.value(),
                offset: acc.byte_offset.map_or(0, |o| o.0),
                count,
                elem: csize,
                align: csize,
                allow_stride: true,
            },
        )?;
        (0..count as usize)
            .map(|i| decode_index(comp, s.elem(i)).ok_or_else(|| "bad index type".to_string()))
            .collect()
    };
    inner().map_err(|e| format!("accessor {index}: {e}"))
}
