//! Ray-traced per-facet inputs of the thermal model (being written).
