//! The film: linear HDR accumulation, AOVs, and EXR/PNG output.
