//! The sea's surface: heights below sea level raised to it, for data that
//! keep the sea floor (ETOPO, GEBCO). A synthetic-vision display draws the
//! sea as the surface an aircraft would meet, not the bathymetry under it,
//! and its horizon is then the sea-level horizon a pilot sees.
//!
//! Raising is conservative for terrain awareness: land below sea level
//! (the Dead Sea shore at -430 m, the Caspian depression, polders) is
//! drawn at sea level, above the real ground, never below it.

/// Sea level, metres: heights below it are raised to it.
pub const SEA_SURFACE_M: f32 = 0.0;

/// Raises every height below [`SEA_SURFACE_M`] to it, leaving no data (NaN)
/// as it is; returns how many were raised.
pub fn raise_to_sea_surface(heights: &mut [f32]) -> u64 {
    let mut raised = 0;
    for h in heights.iter_mut().filter(|h| **h < SEA_SURFACE_M) {
        *h = SEA_SURFACE_M;
        raised += 1;
    }
    raised
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_heights_below_the_sea_are_raised_and_no_data_stays() {
        let mut heights = [-4000.0, -0.5, 0.0, 12.0, f32::NAN, f32::NEG_INFINITY];
        assert_eq!(raise_to_sea_surface(&mut heights), 3);
        assert_eq!(&heights[..4], &[0.0, 0.0, 0.0, 12.0]);
        assert!(heights[4].is_nan());
        assert_eq!(heights[5], 0.0);
    }
}
