//! Reading the NumPy arrays of exports and external lists, with errors that name the file, what
//! it holds and what is accepted.

use std::path::Path;

use npyz::{DType, NpyFile, Order};

use crate::LabError;

fn bad(path: &Path, message: String) -> LabError {
    LabError::Io {
        path: path.display().to_string(),
        message,
    }
}

/// An array of `path` in C order: its shape and its values, of the dtype named by `dtype`
/// (NumPy's `<u4`, `<u8`, `<i4` or `<f4`), checked against `want` (a `None` axis is any length).
pub(crate) fn read<T: npyz::Deserialize>(
    path: &Path,
    dtype: &[&str],
    want: &[Option<u64>],
) -> Result<(Vec<u64>, Vec<T>), LabError> {
    let bytes = std::fs::read(path).map_err(|e| bad(path, e.to_string()))?;
    let npy = NpyFile::new(&bytes[..]).map_err(|e| bad(path, format!("not a NumPy array: {e}")))?;
    let got = match npy.dtype() {
        DType::Plain(t) => t.to_string(),
        other => other.descr(),
    };
    if !dtype.contains(&got.as_str()) {
        return Err(bad(
            path,
            format!("dtype {got}; accepted: {}", dtype.join(" or ")),
        ));
    }
    let shape = npy.shape().to_vec();
    let fits = shape.len() == want.len()
        && shape
            .iter()
            .zip(want)
            .all(|(&s, w)| w.is_none_or(|w| w == s));
    if !fits {
        let want: Vec<String> = want
            .iter()
            .map(|w| w.map_or("any".into(), |w| w.to_string()))
            .collect();
        return Err(bad(
            path,
            format!("shape {shape:?}; expected ({})", want.join(", ")),
        ));
    }
    if shape.len() > 1 && npy.order() != Order::C {
        return Err(bad(path, "Fortran order; write it in C order".into()));
    }
    let values = npy
        .into_vec::<T>()
        .map_err(|e| bad(path, format!("reading the values: {e}")))?;
    Ok((shape, values))
}

/// The `.npy` bytes of `data` as an array of `shape` (C order, little-endian, the dtype of `T`).
pub(crate) fn encode<T: npyz::AutoSerialize + Copy>(
    shape: &[u64],
    data: &[T],
) -> std::io::Result<Vec<u8>> {
    use npyz::WriterBuilder;
    let mut bytes = Vec::new();
    let mut w = npyz::WriteOptions::new()
        .default_dtype()
        .shape(shape)
        .writer(&mut bytes)
        .begin_nd()?;
    w.extend(data.iter().copied())?;
    w.finish()?;
    Ok(bytes)
}

/// `data` as a `uint32` array of `shape`, written whole or not at all.
pub(crate) fn write_u32(path: &Path, shape: &[u64], data: &[u32]) -> Result<(), LabError> {
    let bytes = encode(shape, data).map_err(|e| bad(path, e.to_string()))?;
    crate::write_atomic(path, &bytes)
}
