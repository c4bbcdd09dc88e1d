//! Building refuses bad input with a reason, and the layout arithmetic the
//! file relies on (levels, node order) holds.

use proptest::prelude::*;
use ridgeline::node::{NodeId, NodeLayout};
use ridgeline::pyramid::{build, BuildError, BuildOptions, Silent};
use testkit::pyramid::random_grid;

#[test]
fn bad_grids_and_options_are_refused_with_a_reason() {
    let grid = random_grid(20, 10, 1);
    let refuse = |grid: &ridgeline::dem::ElevationGrid, options: BuildOptions| {
        build(grid, &options, &Silent).err().expect("refused").to_string()
    };
    let mut infinite = grid.clone();
    infinite.heights[3 * 20 + 7] = f32::INFINITY;
    assert!(refuse(&infinite, BuildOptions::default()).contains("(7, 3)"));
    // NaN is no-data, not an error; a grid without any data is.
    let mut nan = grid.clone();
    nan.heights[3 * 20 + 7] = f32::NAN;
    assert!(build(&nan, &BuildOptions::default(), &Silent).is_ok());
    let mut none = grid.clone();
    none.heights.iter_mut().for_each(|h| *h = f32::NAN);
    assert!(refuse(&none, BuildOptions::default()).contains("no post has data"));
    let mut short = grid.clone();
    short.heights.pop();
    assert!(refuse(&short, BuildOptions::default()).contains("199 heights"));
    let mut empty = grid.clone();
    (empty.width, empty.heights) = (0, Vec::new());
    assert!(matches!(
        build(&empty, &BuildOptions::default(), &Silent),
        Err(BuildError::InvalidGrid(_))
    ));
    let mut no_spacing = grid.clone();
    no_spacing.georef.spacing[1] = 0.0;
    assert!(refuse(&no_spacing, BuildOptions::default()).contains("spacing"));
    assert!(refuse(&grid, BuildOptions { node_size: 0, border: 2 }).contains("node size"));
    assert!(refuse(&grid, BuildOptions { node_size: 64, border: 99 }).contains("border"));
}

#[test]
fn a_single_sample_is_a_one_node_pyramid() {
    let grid = random_grid(1, 1, 2);
    let built = build(&grid, &BuildOptions::default(), &Silent).expect("build");
    assert_eq!(built.layout().levels, 1);
    let (posts, summary) = built.node(NodeId::new(0, 0, 0)).expect("root");
    assert!(posts.iter().all(|&h| h == grid.heights[0]));
    assert_eq!((summary.min, summary.max, summary.delta), (grid.heights[0], grid.heights[0], 0.0));
}

proptest! {
    /// The root level is one node, the level below it is not, and listing the
    /// nodes level by level, row by row numbers them 0, 1, 2, ...
    #[test]
    fn levels_end_in_one_root_and_node_indices_are_dense(
        width in 1u32..3000, height in 1u32..3000, node_size in 1u32..200,
    ) {
        let levels = NodeLayout::levels_for([width, height], node_size);
        let layout = NodeLayout { levels, node_size, border: 1, posts: [width, height], spacing_m: [1.0; 2] };
        prop_assert_eq!(layout.nodes_at(levels - 1), [1, 1]);
        if levels > 1 {
            prop_assert_ne!(layout.nodes_at(levels - 2), [1, 1]);
        }
        let mut expected = 0u64;
        for lod in 0..levels {
            let [nx, ny] = layout.nodes_at(lod);
            // Every sample is covered: the nodes span at least the data.
            prop_assert!(nx as u64 * layout.span(lod) >= (width - 1) as u64);
            prop_assert!(ny as u64 * layout.span(lod) >= (height - 1) as u64);
            for (x, y) in [(0, 0), (nx - 1, 0), (0, ny - 1), (nx - 1, ny - 1)] {
                let index = layout.node_index(NodeId::new(lod, x, y));
                prop_assert_eq!(index, Some(expected + y as u64 * nx as u64 + x as u64));
            }
            prop_assert_eq!(layout.node_index(NodeId::new(lod, nx, 0)), None);
            expected += nx as u64 * ny as u64;
        }
        prop_assert_eq!(expected, layout.node_count());
        prop_assert_eq!(layout.node_index(NodeId::new(levels, 0, 0)), None);
    }
}
