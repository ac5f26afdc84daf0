# scene tests
