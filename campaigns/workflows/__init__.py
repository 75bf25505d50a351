"""What an engineer does with campaigns: measured tests, diagnosis, export, design comparison, procedure search."""
