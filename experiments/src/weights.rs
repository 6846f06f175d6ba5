//! A network's variables as plain data, shared by the networks of this crate
//! ([`crate::pilotnet`], [`crate::perception`]): written to ONNX, read back, and turned into
//! candle tensors.

use std::collections::HashMap;

use candle_core::{Device, Tensor};

/// One variable: its name (`conv1.weight`), its shape and its values, row-major.
pub type Weight = (String, Vec<usize>, Vec<f32>);

/// Tensors by name, for `candle_nn::VarBuilder::from_tensors`.
///
/// # Errors
/// candle's, when a shape does not match its data.
pub fn tensors(
    weights: &[Weight],
    device: &Device,
) -> candle_core::Result<HashMap<String, Tensor>> {
    weights
        .iter()
        .map(|(n, s, d)| {
            Ok((
                n.clone(),
                Tensor::from_vec(d.clone(), s.as_slice(), device)?,
            ))
        })
        .collect()
}
