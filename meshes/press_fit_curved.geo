// The press fit of press_fit.geo (a steel pin 15 um oversize in a steel ring, unstructured
// tetrahedra of 1.0 mm on the pin's face and 1.5 mm on the bore) in second-order tetrahedra:
// their midside nodes lie on the cylinders, so the contact surfaces are curved (docs/press_fit.md,
// "Curved contact surfaces"). The same with order = 1 is 26 % off Lamé.
order = 2;
Include "press_fit.geo";
