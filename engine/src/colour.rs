//! The colours an object may have (`Car(color=...)`), one list from which the camera's albedo
//! and the scenario language's check of colour names are both derived.

/// Every colour name with its linear albedo `[r, g, b]` in `[0, 1]` under white light.
pub const COLOURS: [(&str, [f32; 3]); 9] = [
    ("red", [0.75, 0.08, 0.07]),
    ("white", [0.92, 0.92, 0.92]),
    ("black", [0.04, 0.04, 0.05]),
    ("blue", [0.08, 0.18, 0.70]),
    ("green", [0.10, 0.55, 0.15]),
    ("yellow", [0.90, 0.78, 0.10]),
    ("orange", [0.92, 0.45, 0.08]),
    ("silver", [0.70, 0.71, 0.73]),
    ("grey", [0.45, 0.45, 0.45]),
];

/// The albedo of colour `name` (case-insensitive), `None` for a name not in [`COLOURS`].
pub fn albedo(name: &str) -> Option<[f32; 3]> {
    let name = name.to_ascii_lowercase();
    COLOURS.iter().find(|(n, _)| *n == name).map(|(_, a)| *a)
}

/// The colour names, for messages: `red, white, ...`.
pub fn names() -> String {
    COLOURS.map(|(n, _)| n).join(", ")
}

#[cfg(test)]
mod tests {
    #[test]
    fn names_are_found_whatever_their_case_and_unknown_ones_are_not() {
        assert_eq!(super::albedo("Red"), super::albedo("red"));
        assert!(super::albedo("red").is_some());
        assert_eq!(super::albedo("purple"), None);
    }
}
