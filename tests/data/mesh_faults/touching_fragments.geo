// touching.geo extruded without Layers{} and joined by BooleanFragments: the line x = z = 0
// is shared, every facet lies on a cell.
layers = 0;
fragments = 1;
Include "touching.geo";
