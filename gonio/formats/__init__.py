"""File formats: readers and writers of the package's data files."""
