"""The reports: error against run time, written as CSV, Markdown tables and plots."""
