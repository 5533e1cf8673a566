"""The built-in cases, one TOML file each."""
