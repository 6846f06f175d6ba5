/// The light intensity of nominal daylight, at which a camera's fixed exposure is calibrated:
/// a surface of albedo `a` facing the sun reads `255 · a · light / NOMINAL_LIGHT` (clipped at
/// 255). Light is in `[0, 1]`: 0 is night, 1 twice nominal (glare: bright surfaces saturate).
/// The lidar ignores light.
pub const NOMINAL_LIGHT: f64 = 0.5;

/// Extinction coefficient at fog density 1, in 1/m.
pub const FOG_EXTINCTION_PER_M: f64 = 0.5;

/// Meteorological visibility in metres for a fog density in `[0, 1]`: Koschmieder's law
/// `V = 3.912 / σ` (the distance at which contrast falls to 2 %) with extinction
/// `σ = fog · 0.5 /m`. Fog 0 is unlimited (`+inf`), 0.1 is 78 m, 0.5 is 15.6 m, 1 is 7.8 m
/// (very dense fog).
/// The lidar's range is capped at the visibility; the camera (issue 6) fogs with the same σ.
pub fn visibility_m(fog: f64) -> f64 {
    let sigma = fog.clamp(0.0, 1.0) * FOG_EXTINCTION_PER_M;
    if sigma > 0.0 {
        3.912 / sigma
    } else {
        f64::INFINITY
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn visibility_falls_with_fog() {
        assert_eq!(super::visibility_m(0.0), f64::INFINITY);
        assert!((super::visibility_m(1.0) - 7.824).abs() < 1e-9);
        assert!(super::visibility_m(0.5) > super::visibility_m(0.6));
    }
}
