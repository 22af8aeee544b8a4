"""Figures. Functions take arrays and return matplotlib Figures; callers save them."""
