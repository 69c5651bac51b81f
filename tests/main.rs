//! egt's integration tests: one binary, one module per concern.

mod dynamics; // issue 3: inverse dynamics, forces, power flow, efficiency vs independent relations
