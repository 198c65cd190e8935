;;;; tools/fuzz.lisp -- make fuzz: a long campaign of random operation sequences (#M9W5P7).
;;;; SEED (default 1), COUNT sequences (default 1200) and LENGTH operations each (default 150)
;;;; come from the environment.  Prints the figures as Org tables; exit status 1 when a sequence
;;;; broke a promise (its seed and shrunk sequence are printed first).

(load (merge-pathnames "boot.lisp" *load-truename*))

(in-package #:cl-user)

(when (luv-load-systems "luv-physics")
  (sb-ext:exit :code 2))

(flet ((setting (name default)
         (let ((text (uiop:getenv name)))
           (if (and text (string/= text "")) (parse-integer text) default))))
  (let* ((seed (setting "SEED" 1)) (count (setting "COUNT" 1200)) (length (setting "LENGTH" 150))
         (start (get-internal-real-time))
         (figures (funcall (find-symbol "RUN-FUZZ-CAMPAIGN" '#:luv-physics)
                           :seed seed :sequences count :length length :stream *error-output*)))
    (format t "make fuzz SEED=~D COUNT=~D LENGTH=~D~%~%" seed count length)
    (funcall (find-symbol "PRINT-FUZZ-FIGURES" '#:luv-physics) figures
             (/ (- (get-internal-real-time) start) internal-time-units-per-second) *standard-output*)
    (finish-output)
    (sb-ext:exit :code (if (zerop (getf figures :failures)) 0 1))))
