"""Data files shipped with hydroarm (paper tables, loads, parameter sets)."""
