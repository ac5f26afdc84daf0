# gl tests
