//! Error metrics between surfaces (Metro-style `compare`).
