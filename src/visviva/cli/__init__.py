"""The visviva command-line interface."""
