"""The bladed disk: cyclic symmetry, component mode synthesis of N sectors, harmonics, loads, indicators, the
disk's builder."""
