//! Charts: plotters drawing functions over any `DrawingArea`.
