use serde::{Deserialize, Serialize};

/// One point of a [`crate::ParamSpace`], in the generators' normalised coordinates.
///
/// - `discrete[j]` is the level index of the `j`-th discrete parameter (in declaration order),
///   in `0..levels_j`.
/// - `continuous[j]` is the coordinate of the `j`-th continuous parameter, in `[0, 1)`; it maps
///   linearly onto the parameter's interval `[lo, hi)` (see [`crate::ParamSpace::decode`]).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Point {
    /// Level indices of the discrete parameters, one per discrete parameter.
    pub discrete: Vec<u32>,
    /// Coordinates of the continuous parameters in `[0, 1)`, one per continuous parameter.
    pub continuous: Vec<f64>,
}
