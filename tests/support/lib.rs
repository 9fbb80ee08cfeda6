//! Helpers shared by the gate tests.
