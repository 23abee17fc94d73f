//! grainline-toolpaths: placeholder, filled by the toolpaths issue.
