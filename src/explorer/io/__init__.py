"""Input/output layer: scene files (:mod:`explorer.io.scene`, schema and validation of TOML
scenes, presets in ``io/presets/*.toml``) and the HDF5 store (:mod:`explorer.io.store`: format,
atomic commits, reading). The only layer besides ``app`` that imports h5py."""
