//! The whole nc-conform scenario library against the Acme 980: one test per scenario file,
//! named by its path (`cargo test -p nc-conform-vendor-example -- gsk/feed_hold`); scenarios of
//! the dialects it does not run are listed as ignored (the suite prints a `note:` line saying so;
//! see README.md).

nc_conform::conformance_suite!(
    nc_conform_vendor_example::Acme980::new,
    concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenarios")
);
