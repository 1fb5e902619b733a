"""Small dense linear algebra, rank decisions and eigensolvers shared by every layer."""
