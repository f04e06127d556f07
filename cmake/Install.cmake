# Install rules and package export (filled in by the install work).
