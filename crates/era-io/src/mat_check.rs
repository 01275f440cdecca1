//! A structural check of MAT v5 bytes before `matrw` parses them.
//!
//! `matrw` sizes its buffers from the dimensions and byte counts in the file. A
//! malformed file can declare an array of 10¹² elements in a few hundred bytes, and
//! the allocation then aborts the process (an allocation failure is not a panic and
//! cannot be caught). This walk reads every element's tag, and every array's
//! dimensions, and refuses a file where a declared size exceeds the bytes that can
//! hold it. Compressed elements are inflated with `flate2`, capped at what zlib can
//! produce from their compressed size.
//!
//! Written by hand because it checks exactly the sizes `matrw` trusts; it reads no
//! values.

/// Data types of the level-5 format used here.
const MI_INT32: u32 = 5;
const MI_UINT32: u32 = 6;
const MI_MATRIX: u32 = 14;
const MI_COMPRESSED: u32 = 15;

/// zlib's deflate cannot expand data by more than about 1032:1.
const ZLIB_MAX_RATIO: usize = 1032;

/// Deepest nesting of cells and structs accepted.
const MAX_DEPTH: usize = 32;

struct Reader<'a> {
    bytes: &'a [u8],
    big_endian: bool,
}

impl Reader<'_> {
    fn u32_at(&self, at: usize) -> Result<u32, String> {
        let b: [u8; 4] = self
            .bytes
            .get(at..at + 4)
            .and_then(|s| s.try_into().ok())
            .ok_or_else(|| format!("byte {at}: the file ends inside an element tag"))?;
        Ok(if self.big_endian {
            u32::from_be_bytes(b)
        } else {
            u32::from_le_bytes(b)
        })
    }

    /// The tag at `at`: (type, byte count, offset of the data, offset after the
    /// element padded to 8 bytes).
    fn tag(&self, at: usize, end: usize) -> Result<(u32, usize, usize, usize), String> {
        let first = self.u32_at(at)?;
        if first >> 16 != 0 {
            // Small data element: type and size in one word, up to 4 bytes of data.
            let (ty, n) = (first & 0xffff, (first >> 16) as usize);
            if n > 4 {
                return Err(format!(
                    "byte {at}: a small element claims {n} bytes (at most 4)"
                ));
            }
            return Ok((ty, n, at + 4, at + 8));
        }
        let n = self.u32_at(at + 4)? as usize;
        let data = at + 8;
        // Elements are padded to 8 bytes, except compressed ones.
        let padded = if first == MI_COMPRESSED {
            n
        } else {
            n.div_ceil(8) * 8
        };
        let after = data
            .checked_add(padded)
            .ok_or_else(|| format!("byte {at}: element size overflows"))?;
        // The last element may omit its padding.
        if data + n > end {
            return Err(format!(
                "byte {at}: an element of {n} bytes runs past the end of its container ({} bytes left)",
                end.saturating_sub(data)
            ));
        }
        Ok((first, n, data, after.min(end.max(data + n))))
    }

    /// Checks one miMATRIX element's content, `data..data+n`.
    fn matrix(&self, data: usize, n: usize, depth: usize) -> Result<(), String> {
        if depth > MAX_DEPTH {
            return Err(format!(
                "byte {data}: arrays nested deeper than {MAX_DEPTH}"
            ));
        }
        let end = data + n;
        if n == 0 {
            return Ok(()); // an empty placeholder element
        }
        // Array flags.
        let (ty, flags_n, flags_at, mut at) = self.tag(data, end)?;
        if ty != MI_UINT32 || flags_n < 8 {
            return Err(format!("byte {data}: array flags missing"));
        }
        let class = self.u32_at(flags_at)? & 0xff;
        match class {
            1 | 2 | 4..=15 => {}
            3 => {
                return Err(format!(
                    "byte {data}: MATLAB objects (class 3) are not supported"
                ))
            }
            c => return Err(format!("byte {data}: unknown array class {c}")),
        }
        // Dimensions.
        let (ty, dims_n, dims_at, next) = self.tag(at, end)?;
        if ty != MI_INT32 || dims_n % 4 != 0 || dims_n < 8 {
            return Err(format!("byte {at}: array dimensions missing"));
        }
        let mut count: u128 = 1;
        for k in 0..dims_n / 4 {
            let d = self.u32_at(dims_at + 4 * k)? as i32;
            if d < 0 {
                return Err(format!("byte {dims_at}: a negative dimension ({d})"));
            }
            count = count.saturating_mul(d as u128);
        }
        at = next;
        // Name.
        let (_, _, _, next) = self.tag(at, end)?;
        at = next;
        // Every element needs at least one byte of the array's content (numeric data
        // may be stored in 1-byte types); a cell or struct element needs a tag.
        let room = end.saturating_sub(at) as u128;
        let per_element: u128 = match class {
            1 | 2 => 8, // cell, struct: a nested element tag each
            _ => 1,
        };
        if class == 5 {
            // Sparse: sizes are in the index arrays, checked as elements below.
        } else if count.saturating_mul(per_element) > room.max(8) {
            return Err(format!(
                "byte {data}: dimensions of {count} elements do not fit in the {room} bytes that follow"
            ));
        }
        // Nested elements (cells, struct fields) and data subelements.
        while at + 8 <= end {
            let (ty, sub_n, sub_at, next) = self.tag(at, end)?;
            if ty == MI_MATRIX {
                self.matrix(sub_at, sub_n, depth + 1)?;
            }
            if next <= at {
                break;
            }
            at = next;
        }
        Ok(())
    }
}

/// Walks the top-level elements of MAT v5 bytes (after the 128-byte header).
pub(crate) fn check(bytes: &[u8]) -> Result<(), String> {
    let big_endian = match bytes.get(126..128) {
        Some(b"IM") => false,
        Some(b"MI") => true,
        _ => return Err("byte 126: no endian indicator ('IM' or 'MI')".into()),
    };
    let top = Reader { bytes, big_endian };
    let mut at = 128;
    while at + 8 <= bytes.len() {
        let (ty, n, data, next) = top.tag(at, bytes.len())?;
        match ty {
            MI_MATRIX => top.matrix(data, n, 0)?,
            MI_COMPRESSED if n > 0 => {
                let inflated = inflate(&bytes[data..data + n])
                    .map_err(|e| format!("byte {at}: compressed element: {e}"))?;
                let inner = Reader {
                    bytes: &inflated,
                    big_endian,
                };
                let (ty, m, inner_data, _) = inner.tag(0, inflated.len())?;
                if ty == MI_MATRIX {
                    inner
                        .matrix(inner_data, m, 0)
                        .map_err(|e| format!("compressed element at byte {at}, inflated {e}"))?;
                }
            }
            _ => {}
        }
        if next <= at {
            break;
        }
        at = next;
    }
    Ok(())
}

/// Inflates a zlib stream, refusing more output than zlib can produce from its size.
fn inflate(compressed: &[u8]) -> Result<Vec<u8>, String> {
    use std::io::Read;
    let cap = compressed
        .len()
        .saturating_mul(ZLIB_MAX_RATIO)
        .saturating_add(64);
    let mut out = Vec::new();
    flate2::read::ZlibDecoder::new(compressed)
        .take(cap as u64 + 1)
        .read_to_end(&mut out)
        .map_err(|e| format!("corrupt zlib data ({e})"))?;
    if out.len() > cap {
        return Err("inflates beyond what zlib can produce from it".into());
    }
    Ok(out)
}
