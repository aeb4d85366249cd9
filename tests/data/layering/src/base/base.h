/* The lowest module of the fixture: includes nothing. */
