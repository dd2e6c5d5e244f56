"""The reduced model: its node map, its matrices and forces, its file."""
