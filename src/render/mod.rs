//! The render pipeline: scene → exposure/thermal → primary rays → radiometry → sensor → outputs (being written).
