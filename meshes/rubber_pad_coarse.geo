// cases/rubber_pad.toml on elements twice as large (make test's variant).
DefineConstant[ h = 2.5e-3 ];
Include "rubber_pad.geo";
