"""Demo scenes and the script that renders them (`make demo`)."""
