//! Mitsuba 3's TensorFile format (include/mitsuba/core/tensor.h, src/core/tensor.cpp of
//! Mitsuba 3.9.1), which its `sunsky` datasets come in: the 12 bytes "tensor_file\0", a
//! version (2 bytes), the number of fields (u32), then per field its name length (u16), name,
//! number of dimensions (u16), element type (u8, drjit's VarType: 10 float32, 11 float64),
//! the offset of its data from the file's start (u64) and each dimension (u64). Data are
//! little-endian and row-major.

/// One field of a tensor file, its values widened to f64 (no float32 value changes).
#[derive(Debug, Clone, PartialEq)]
pub struct Field {
    pub name: String,
    pub shape: Vec<usize>,
    pub values: Vec<f64>,
}

/// Every field of the tensor file `bytes`, in the order its header lists them.
pub fn parse(bytes: &[u8]) -> Result<Vec<Field>, String> {
    let mut at = 0usize;
    let mut take = |n: usize| -> Result<&[u8], String> {
        let slice = bytes
            .get(at..at + n)
            .ok_or_else(|| format!("tensor file truncated at byte {at}"))?;
        at += n;
        Ok(slice)
    };
    if take(12)? != b"tensor_file\0" {
        return Err("not a tensor file (no \"tensor_file\" header)".into());
    }
    let version = take(2)?;
    if version[1] != 0 {
        return Err(format!(
            "tensor file version {version:?} is not one Mitsuba reads"
        ));
    }
    let u16_of = |b: &[u8]| u16::from_le_bytes([b[0], b[1]]);
    let u64_of = |b: &[u8]| u64::from_le_bytes(b.try_into().expect("8 bytes"));
    let count = u32::from_le_bytes(take(4)?.try_into().expect("4 bytes"));
    let mut fields = Vec::new();
    for _ in 0..count {
        let length = u16_of(take(2)?) as usize;
        let name = String::from_utf8(take(length)?.to_vec())
            .map_err(|_| "a tensor file field name is not UTF-8".to_string())?;
        let ndim = u16_of(take(2)?) as usize;
        let dtype = take(1)?[0];
        let offset = u64_of(take(8)?) as usize;
        let shape = (0..ndim)
            .map(|_| take(8).map(|b| u64_of(b) as usize))
            .collect::<Result<Vec<_>, _>>()?;
        let size: usize = shape.iter().product();
        let width = match dtype {
            10 => 4,
            11 => 8,
            other => return Err(format!("field {name}: element type {other} is not a float")),
        };
        let data = offset
            .checked_add(size * width)
            .and_then(|end| bytes.get(offset..end))
            .ok_or_else(|| format!("field {name}: its data lie past the file's end"))?;
        let values = data
            .chunks_exact(width)
            .map(|b| match width {
                4 => f32::from_le_bytes(b.try_into().expect("4 bytes")) as f64,
                _ => f64::from_le_bytes(b.try_into().expect("8 bytes")),
            })
            .collect();
        fields.push(Field {
            name,
            shape,
            values,
        });
    }
    Ok(fields)
}
