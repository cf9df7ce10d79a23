//! Tests of the app: update driven by messages, and whole-screen snapshots.
