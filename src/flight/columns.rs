//! The quantities a camera path row holds, their names in a CSV header and the
//! ranges Ridgeline accepts for them. Path construction and the CSV reader both
//! check values here, so a programmatic path and a file obey the same rules.

/// One column of a camera path.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Column {
    /// `t`: seconds.
    Time,
    /// `x`: metres east of the dataset's south-west post.
    X,
    /// `y`: metres north of the dataset's south-west post.
    Y,
    /// `lat`: latitude, degrees (geographic datasets only).
    Lat,
    /// `lon`: longitude, degrees (geographic datasets only).
    Lon,
    /// `alt`: metres above mean sea level.
    Altitude,
    /// `heading`: degrees clockwise from true north.
    Heading,
    /// `pitch`: degrees, positive nose up.
    Pitch,
    /// `roll`: degrees, positive right wing down.
    Roll,
}

/// Why a value cannot be used.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ValueProblem {
    /// The cell holds nothing but whitespace.
    #[error("the cell is empty")]
    Empty,
    /// The cell (as written, trimmed) does not parse as a number.
    #[error("`{0}` is not a number")]
    NotANumber(String),
    /// The value as written (or printed, for a value that came from code).
    #[error("`{0}` is not a finite number")]
    NotFinite(String),
    /// The value is finite but outside the column's accepted range.
    #[error("{value} is outside [{min}, {max}] {unit}{why}")]
    OutOfRange {
        /// The value given.
        value: f64,
        /// Smallest accepted value, in `unit`.
        min: f64,
        /// Largest accepted value, in `unit`.
        max: f64,
        /// Unit of the column: `seconds`, `metres` or `degrees`.
        unit: &'static str,
        /// Why the bounds are where they are (empty, or a parenthesis led by a space).
        why: &'static str,
    },
}

impl Column {
    /// Every column, in the order a written CSV uses (x,y form first).
    pub const ALL: [Column; 9] = [
        Column::Time,
        Column::X,
        Column::Y,
        Column::Lat,
        Column::Lon,
        Column::Altitude,
        Column::Heading,
        Column::Pitch,
        Column::Roll,
    ];

    /// The header name.
    pub fn name(self) -> &'static str {
        match self {
            Column::Time => "t",
            Column::X => "x",
            Column::Y => "y",
            Column::Lat => "lat",
            Column::Lon => "lon",
            Column::Altitude => "alt",
            Column::Heading => "heading",
            Column::Pitch => "pitch",
            Column::Roll => "roll",
        }
    }

    /// The column a header name (already trimmed, any case) stands for.
    pub fn from_name(name: &str) -> Option<Column> {
        Column::ALL.into_iter().find(|column| column.name().eq_ignore_ascii_case(name))
    }

    /// Inclusive accepted range, unit and the reason for the bounds.
    fn range(self) -> (f64, f64, &'static str, &'static str) {
        match self {
            // Differences of times this size are still exact to nanoseconds.
            Column::Time => (-1e7, 1e7, "seconds", ""),
            Column::X | Column::Y => (
                -5e7,
                5e7,
                "metres",
                " (a global grid's chart is 40 075 km wide; farther is off the earth)",
            ),
            Column::Lat => (-90.0, 90.0, "degrees", ""),
            // [-180, 180] or [0, 360] as data store them, and one turn
            // more for a path that crosses a grid's seam.
            Column::Lon => (-360.0, 360.0, "degrees", ""),
            Column::Altitude => {
                (-11_000.0, 100_000.0, "metres", " (the deepest ocean to the edge of space)")
            }
            Column::Heading => (-360.0, 360.0, "degrees", ""),
            Column::Pitch => (-90.0, 90.0, "degrees", ""),
            Column::Roll => (-180.0, 180.0, "degrees", ""),
        }
    }

    /// Accepts `value` for this column or says why not.
    pub fn check(self, value: f64) -> Result<f64, ValueProblem> {
        if !value.is_finite() {
            return Err(ValueProblem::NotFinite(value.to_string()));
        }
        let (min, max, unit, why) = self.range();
        if value < min || value > max {
            return Err(ValueProblem::OutOfRange { value, min, max, unit, why });
        }
        Ok(value)
    }

    /// Reads one CSV cell (surrounding whitespace allowed) as this column's value.
    pub fn parse(self, cell: &str) -> Result<f64, ValueProblem> {
        let text = cell.trim();
        if text.is_empty() {
            return Err(ValueProblem::Empty);
        }
        let value: f64 = text.parse().map_err(|_| ValueProblem::NotANumber(text.to_string()))?;
        // Name the cell as written: `1e400` overflows to inf.
        self.check(value).map_err(|problem| match problem {
            ValueProblem::NotFinite(_) => ValueProblem::NotFinite(text.to_string()),
            other => other,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The CSV reader indexes a value array by `column as usize`.
    #[test]
    fn discriminants_are_positions_in_all() {
        for (index, column) in Column::ALL.into_iter().enumerate() {
            assert_eq!(column as usize, index);
            assert_eq!(Column::from_name(&column.name().to_uppercase()), Some(column));
        }
    }
}
