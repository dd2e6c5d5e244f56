"""Pictures: pyvista fields, matplotlib charts, the HTML report."""
