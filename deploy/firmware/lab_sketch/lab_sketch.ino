// The lab's spin-down sketch as it should have been printed: the handout declared
// `float data:` (a colon), which does not compile. Behaviour unchanged: every ~20 ms it reads
// the back-EMF on A0 (10-bit ADC, 0-5 V) and prints "millis<TAB>volts" (volts with two
// decimals, Serial.println(float)) at 9600 baud, CR LF.
float data;

void setup() {
  Serial.begin(9600);
}

void loop() {
  data = analogRead(A0) * 5.0 / 1023;
  Serial.print(millis());
  Serial.print("\t");
  Serial.println(data);
  delay(20);
}
