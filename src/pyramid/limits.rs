//! The limits of a pyramid this crate builds and opens: node size, border and
//! depth. Building and opening check them with the same functions, so a file
//! the builder writes always opens and the messages agree.

use crate::node::NodeLayout;

/// Largest node size in cells (posts per side must stay a sane vertex count).
pub const MAX_NODE_SIZE: u32 = 4096;
/// Largest border in posts.
pub const MAX_BORDER: u32 = 16;
/// Deepest pyramid a file may declare (2^31 posts per side at node size 1).
pub const MAX_LEVELS: u8 = 32;
/// Most level-0 posts per side of the union of all layers.
pub const MAX_POSTS_PER_SIDE: u64 = 1 << 30;

/// Why `node_size` and `border` are out of range, if they are.
pub(crate) fn check_node(node_size: u32, border: u32) -> Result<(), String> {
    if !(1..=MAX_NODE_SIZE).contains(&node_size) || border > MAX_BORDER {
        return Err(format!(
            "node size {node_size} must be 1..={MAX_NODE_SIZE} and border {border} at most {MAX_BORDER}"
        ));
    }
    Ok(())
}

/// Why a pyramid of `levels` levels is too deep, if it is.
pub(crate) fn check_levels(levels: u8) -> Result<(), String> {
    if !(1..=MAX_LEVELS).contains(&levels) {
        return Err(format!("{levels} levels: must be 1..={MAX_LEVELS}; use larger nodes"));
    }
    Ok(())
}

/// Why `layout` cannot be a pyramid this crate builds, if it cannot.
pub(crate) fn check_layout(layout: &NodeLayout) -> Result<(), String> {
    check_node(layout.node_size, layout.border)?;
    check_levels(layout.levels)?;
    if layout.posts.contains(&0) {
        return Err(format!("posts {:?}: must be at least 1 a side", layout.posts));
    }
    if layout.levels != NodeLayout::levels_for(layout.posts, layout.node_size) {
        return Err(format!("{} levels do not end in one root node", layout.levels));
    }
    if !layout.spacing_m.iter().all(|s| s.is_finite() && *s > 0.0) {
        return Err(format!("spacing {:?} m is not positive", layout.spacing_m));
    }
    Ok(())
}
