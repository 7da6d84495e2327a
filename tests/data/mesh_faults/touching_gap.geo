// touching.geo with the fix the error advises: the cylinder starts 1e-6 above the block.
g0 = 1e-6;
Include "touching.geo";
