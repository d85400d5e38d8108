"""GeneratePath service: tricks as pose sequences, from YAML."""
