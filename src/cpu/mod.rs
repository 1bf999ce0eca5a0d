//! CPU mirrors of the WGSL kernels, one file per kernel with the same name. Their loops keep the
//! shader's shape (workgroups, local invocations, the same guards) so the two read side by side;
//! they are the reference every GPU result is compared with.

mod cell_keys;

pub use cell_keys::cell_keys;
