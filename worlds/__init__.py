"""Kitchen and item URDFs (primitives only) and the shipped setups, installed as the
package data `cramlite.worlds` (found with importlib.resources, never by path)."""
