//! Gmsh MSH 4.1 ASCII reader (in progress).
