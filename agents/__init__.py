"""Reference controllers, training and evaluation for the connenv environments."""
