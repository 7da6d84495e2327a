"""Problem data of the papers (geometries, loads, materials, reference tables); no algorithms."""
